// A job kind's teaching defaults (schema job_kinds[].teach): the preview's colouring that shows
// its method, set when the page turns to the kind, and the backdrop drawn behind its toolpath
// after a run (an axisymmetric path's platform).
import { state } from "./state.js";
import { MSG } from "./protocol.js";
import { $ } from "./util.js";
import { jobKind, missingFiles } from "./design.js";
import { workers } from "./worker-client.js";

/**
 * The kind's teaching defaults (schema job_kinds[].teach), on a change of kind: the preview's
 * colouring that shows the method (a graded scaffold by bead width, its density; a foam by
 * speed, V*).
 */
export function teachKind(kind) {
  const mode = kind?.teach?.color_by;
  const select = $("color-by");
  if (!mode || !select || ![...select.options].some((o) => o.value === mode) || select.value === mode) return;
  select.value = mode;
  select.dispatchEvent(new Event("change"));
}

/**
 * After a run: the kind's backdrop view (teach.backdrop, a lines3d view at index 0) drawn
 * behind the toolpath in the preview, e.g. the platform an axisymmetric path lies on; removed
 * for a kind without one.
 */
export async function showBackdrop() {
  const view = jobKind().teach?.backdrop;
  if (!state.preview) return;
  if (!view || missingFiles().length) {
    state.preview.setBackdrop(null);
    return;
  }
  try {
    const res = await workers.request({ type: MSG.INSPECT, design: state.json, view, index: 0, key: "backdrop" });
    if (!res.stale && res.shape === "lines3d") state.preview.setBackdrop(res.data);
  } catch {
    state.preview.setBackdrop(null); // the view's own card says what went wrong
  }
}
