// What a picture's caption (and the comparison) says about a design: its name and the settings
// whose values differ from another design's, as "path = value unit". The reference for a
// caption is the job kind's default design: the default design (defaultDesign()) switched to
// the design's job kind, which setField fills with that kind's default job. Units and
// percentages come from the schema's fields. No state of its own.
import { state } from "./state.js";

/** Keys that say nothing about how a result was made. */
const SKIP = new Set(["version", "name", "date", "description"]);
/** A value longer than this is cut (start G-code, a file's embedded bytes). */
const VALUE_CHARS = 32;
/** Settings listed in a caption before "and N more". */
const CAPTION_SETTINGS = 12;

/** The job kind's default design for `design` (parsed), or null. */
export function defaultsFor(design) {
  if (!state.weft) return null;
  let json = state.weft.defaultDesign();
  const kind = design?.job?.kind;
  if (kind && kind !== JSON.parse(json).job?.kind) {
    try {
      json = state.weft.setField(json, "job.kind", JSON.stringify(kind));
    } catch { /* an unknown kind: compared with the default design */ }
  }
  return JSON.parse(json);
}

/**
 * Leaf settings of `b` whose values differ from `a`'s: [{path, from, to}] as display strings
 * (units added). Arrays count as one value; embedded file bytes are left out.
 */
export function settingsDiff(a, b) {
  const out = [];
  const fields = new Map((state.schema.fields ?? []).map((f) => [f.path, f]));
  const walk = (x, y, path) => {
    const isObj = (v) => v && typeof v === "object" && !Array.isArray(v);
    if (isObj(x) || isObj(y)) {
      const keys = new Set([...Object.keys(isObj(x) ? x : {}), ...Object.keys(isObj(y) ? y : {})]);
      for (const k of keys) {
        if ((!path && SKIP.has(k)) || k === "embedded") continue;
        walk(isObj(x) ? x[k] : undefined, isObj(y) ? y[k] : undefined, path ? `${path}.${k}` : k);
      }
      return;
    }
    if (JSON.stringify(x) === JSON.stringify(y)) return;
    const f = fields.get(path);
    out.push({ path, from: shown(x, f), to: shown(y, f) });
  };
  walk(a ?? {}, b ?? {}, "");
  return out;
}

/** A value as a caption shows it: numbers trimmed, a unit or percent from its field, long text cut. */
function shown(v, field) {
  if (v === undefined || v === null) return "–";
  let text;
  if (typeof v === "number" && field?.percent) return `${trim(v * 100)} %`;
  if (typeof v === "number") text = trim(v);
  else if (Array.isArray(v)) text = v.every((e) => typeof e === "number") ? v.map(trim).join(" × ") : JSON.stringify(v);
  else text = typeof v === "string" ? v.replace(/\s+/g, " ") : JSON.stringify(v);
  if (text.length > VALUE_CHARS) text = `${text.slice(0, VALUE_CHARS - 1)}…`;
  return field?.unit && typeof v !== "string" ? `${text} ${field.unit}` : text;
}

const trim = (x) => String(Number(x.toPrecision(6)));

/**
 * A picture's caption: {title, lines} — "name — what", then the settings that differ from the
 * job kind's defaults ("path = value unit"), or what the result was read from.
 * @param {Object|null} design  the design shown ({gcodeFile} for a G-code read as it is)
 */
export function captionOf(design, what) {
  const name = String(design?.name ?? "weft");
  const title = what ? `${name} — ${what}` : name;
  if (!design) return { title, lines: [] };
  if (design.gcodeFile) return { title, lines: [`G-code read as it is: ${design.gcodeFile}`] };
  const diff = settingsDiff(defaultsFor(design), design);
  if (!diff.length) return { title, lines: [`${kindLabel(design)} job, default settings`] };
  const listed = diff.slice(0, CAPTION_SETTINGS).map((d) => `${d.path} = ${d.to}`);
  const more = diff.length > CAPTION_SETTINGS ? [`and ${diff.length - CAPTION_SETTINGS} more`] : [];
  return { title, lines: [`${kindLabel(design)} job, changed from the defaults: ${[...listed, ...more].join(" · ")}`] };
}

function kindLabel(design) {
  const kind = design?.job?.kind;
  return state.schema.job_kinds.find((k) => k.name === kind)?.label ?? kind ?? "weft";
}
