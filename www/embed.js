// The embedded weft (embed.html#d=…&fields=a,b opens index.html?embed#…): the preview, the
// step-through open, the fields the link names and a link to the full page, for course pages.
// A page that embeds it talks to it with postMessage:
//   in:  {type: "weft:set", path, value}   one design field (value: any JSON value)
//        {type: "weft:run"}                run the design
//        {type: "weft:step", index}        show step `index` (0-based) of "How it works"
//   out: {type: "weft:ready", kind, steps}   once the page is ready (steps: their titles)
//        {type: "weft:result", stats}        after each run: the statistics as numbers, keyed
//                                            as in `weft analyze --json`
//        {type: "weft:error", message}       a plain sentence (a refused field, a failed run)
// Messages come only from the embedding page (window.parent). The embedded page keeps no design
// in this browser's storage, so it never replaces the design of a full weft page opened here.
import { state } from "./state.js";
import { $, el } from "./util.js";
import { tellParent } from "./messages.js";
import { setFields } from "./design.js";
import { renderForm } from "./form.js";
import { runDesign } from "./actions.js";
import { goToStep, setOpen, stepsStatus } from "./steps.js";

/** The design paths the link names (`&fields=a,b`), in the link's order. */
function linkedFields() {
  const params = new URLSearchParams(location.hash.replace(/^#/, ""));
  return (params.get("fields") ?? "").split(",").map((s) => s.trim()).filter(Boolean).slice(0, 12);
}

/** Sets the page up as the embedded weft; call once the page is wired and the schema known. */
export function startEmbed() {
  if (!state.embedded) return;
  document.body.classList.add("embed");
  const fields = linkedFields();
  // The full page, with the same design (without the embed's field list).
  const open = el("a", { id: "embed-open", className: "button", target: "_blank", rel: "noopener", textContent: "Open in weft ↗" });
  const refreshLink = () => {
    const params = new URLSearchParams(location.hash.replace(/^#/, ""));
    params.delete("fields");
    const hash = params.toString();
    open.href = `${location.pathname.replace(/[^/]*$/, "")}index.html${hash ? `#${decodeURIComponent(hash)}` : ""}`;
  };
  refreshLink();
  window.addEventListener("hashchange", refreshLink);
  $("slice").after(open);
  // Only the named fields show in the form (form.js filters them, also after a kind change).
  state.embedFields = fields;
  renderForm();
  $("schema-fields").hidden = fields.length === 0;
  document.body.classList.toggle("embed-no-fields", fields.length === 0);
  setOpen(true);
  window.addEventListener("message", onMessage);
  const steps = (state.steps?.list ?? []).map((s) => s.title);
  tellParent({ type: "weft:ready", kind: state.design?.job?.kind ?? null, steps, threads: state.client.threads.asked });
}

function onMessage(e) {
  if (e.source !== window.parent || window.parent === window) return;
  const m = e.data;
  if (!m || typeof m !== "object" || typeof m.type !== "string" || !m.type.startsWith("weft:")) return;
  switch (m.type) {
    case "weft:set": {
      if (typeof m.path !== "string" || !m.path) return tellParent({ type: "weft:error", message: "weft:set needs a path, e.g. {type: \"weft:set\", path: \"job.paths.method\", value: \"euler\"}." });
      let value;
      try {
        value = JSON.stringify(m.value);
      } catch {
        value = undefined;
      }
      if (value === undefined) return tellParent({ type: "weft:error", message: `weft:set ${m.path}: the value must be a JSON value (a number, a string, true or false).` });
      const problem = setFields([[m.path, value]]);
      if (problem) tellParent({ type: "weft:error", message: problem });
      return;
    }
    case "weft:run": {
      runDesign();
      return;
    }
    case "weft:step": {
      const count = stepsStatus().count;
      const i = Number(m.index);
      if (!Number.isInteger(i) || i < 0 || i >= count) {
        return tellParent({ type: "weft:error", message: `weft:step: index ${m.index} is not a step of this design (0 to ${count - 1}).` });
      }
      goToStep(i);
      return;
    }
    default:
      tellParent({ type: "weft:error", message: `Unknown message ${m.type}: weft takes weft:set, weft:run and weft:step.` });
  }
}
