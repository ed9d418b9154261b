// One `inspect` request for a view the page shows (a view card, a step of How it works, the
// preview's backdrop): it says which input is missing instead of asking, shows "…" while the
// worker works, drops an answer a newer request of the same holder replaced, and puts a
// failure's sentence in the holder's line.
import { state } from "./state.js";
import { MSG } from "./protocol.js";
import { messageOf, setMessage } from "./util.js";
import { missingFiles } from "./design.js";
import { workers } from "./worker-client.js";

/**
 * Asks for `view` at `index` for `holder` (an object with a `seq` counter; `key` names the
 * worker's request slot, so a newer one cancels it). `line`: the element that says what is
 * happening; `what`: what the missing-input sentence calls it ("this step"). Resolves to the
 * answer, or null when there is none to show (missing input, replaced, failed: `onError` then
 * runs after the sentence is shown).
 */
export async function inspectView(holder, line, { view, index, key, what = "this", onError = null }) {
  const mine = ++holder.seq;
  const missing = missingFiles();
  if (missing.length) {
    line.textContent = `load ${missing.map((m) => m.name).join(", ")} to see ${what}`;
    return null;
  }
  line.textContent = "…";
  line.classList.remove("field-error");
  let res;
  try {
    res = await workers.request({ type: MSG.INSPECT, design: state.json, view, index, key });
  } catch (err) {
    if (mine === holder.seq && !err.cancelled) {
      setMessage(line, messageOf(err));
      line.classList.add("field-error");
      onError?.(err);
    }
    return null;
  }
  return mine === holder.seq && !res.stale ? res : null;
}
