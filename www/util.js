// Small helpers the page's modules share: the element lookup, messages shown as text,
// numbers and sizes as a person reads them, file names, and saving bytes as a download.
// No state of its own.

export const $ = (id) => document.getElementById(id);

/**
 * An element `tag` with `props` set on it (className, id, textContent, type, …; `attrs`: an
 * object of attributes) and `children` appended.
 */
export function el(tag, props = {}, ...children) {
  const { attrs, ...rest } = props;
  const e = Object.assign(document.createElement(tag), rest);
  for (const [k, v] of Object.entries(attrs ?? {})) e.setAttribute(k, v);
  e.append(...children);
  return e;
}

/** A `<button type="button">` of class `className` showing `text`, hidden unless `hidden` is false. */
export function button(className, text = "", hidden = true) {
  const b = document.createElement("button");
  b.type = "button";
  b.className = className;
  b.textContent = text;
  b.hidden = hidden;
  return b;
}

/** Bytes as a person reads them. */
export function humanBytes(n) {
  const units = ["bytes", "KiB", "MiB", "GiB"];
  let i = 0;
  while (n >= 1024 && i < units.length - 1) {
    n /= 1024;
    i++;
  }
  return `${n >= 100 || i === 0 ? Math.round(n) : n.toFixed(1)} ${units[i]}`;
}

/**
 * Shows a message from the core as text. Its `quoted` parts (a command, a setting's path) are
 * shown as code, without the backticks: made as text nodes and <code> elements, never parsed
 * as HTML. An unpaired backtick stays as it is.
 */
export function setMessage(el, message) {
  const parts = String(message ?? "").split("`");
  if (parts.length % 2 === 0) {
    const last = parts.pop();
    parts[parts.length - 1] += `\`${last}`;
  }
  el.replaceChildren(...parts.map((part, i) => {
    if (i % 2 === 0) return part;
    const code = document.createElement("code");
    code.textContent = part;
    return code;
  }));
}

export function messageOf(err) {
  if (err instanceof Error) return err.message || String(err);
  return typeof err === "string" ? err : JSON.stringify(err);
}

export function getPath(obj, path) {
  return path.split(".").reduce((o, k) => (o == null ? undefined : o[k]), obj);
}

export function titleCase(s) {
  return s.charAt(0).toUpperCase() + s.slice(1);
}

export function formatBytes(n) {
  if (n < 1024) return `${n} B`;
  if (n < 1024 * 1024) return `${(n / 1024).toFixed(1)} KiB`;
  return `${(n / 1024 / 1024).toFixed(1)} MiB`;
}

export function formatDuration(s) {
  if (typeof s !== "number" || !Number.isFinite(s)) return "–";
  const t = Math.round(s);
  const h = Math.floor(t / 3600);
  const m = Math.floor((t % 3600) / 60);
  const sec = t % 60;
  return `${h}:${String(m).padStart(2, "0")}:${String(sec).padStart(2, "0")}`;
}

export function extOf(name) {
  const i = name.lastIndexOf(".");
  return i < 0 ? "" : name.slice(i).toLowerCase();
}

/** A file name without folders and extension, as a design name. */
export function fileStem(name) {
  const base = String(name).split(/[\\/]/).pop() ?? "";
  const i = base.lastIndexOf(".");
  return (i > 0 ? base.slice(0, i) : base).replace(/[\u0000-\u001f\u007f]/g, "").trim().slice(0, 80);
}

export function download(data, name, type) {
  const url = URL.createObjectURL(new Blob([data], { type }));
  const a = document.createElement("a");
  a.href = url;
  a.download = name;
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10000);
}
