// The page's error and notice bars (#error, #notice): what went wrong, and what the page did
// or asks (with buttons running the offered actions). When a worker crash was last shown is
// kept in state.crashShownAt, so a result does not hide it at once.
import { state } from "./state.js";
import { $, setMessage } from "./util.js";

export function showError(message) {
  tellParent({ type: "weft:error", message: String(message) });
  setMessage($("error-text"), message);
  $("error").hidden = false;
  if (/^The worker (stopped|keeps)/.test(message)) state.crashShownAt = Date.now();
}
export function hideError() {
  $("error").hidden = true;
}
export function hideErrorUnlessCrash() {
  if (Date.now() - state.crashShownAt > 8000) hideError();
}
/**
 * Shows a notice (as text); with `link`, a read-only field holding it; with `action` (one or
 * a list of {label, title?, run}), buttons that close the notice and run their action.
 */
export function showNotice(message, link, action) {
  const text = $("notice-text");
  setMessage(text, message);
  for (const a of Array.isArray(action) ? action : action ? [action] : []) {
    const button = document.createElement("button");
    button.type = "button";
    button.className = "notice-action";
    button.textContent = a.label;
    if (a.title) button.title = a.title;
    button.addEventListener("click", () => {
      $("notice").hidden = true;
      a.run();
    });
    text.append(" ", button);
  }
  if (link) {
    const input = document.createElement("input");
    input.id = "share-url";
    input.readOnly = true;
    input.value = link;
    input.setAttribute("aria-label", "Share link");
    input.addEventListener("focus", () => input.select());
    text.append(" ", input);
  }
  $("notice").hidden = false;
}

/** Posts to the page that embeds this one (embed.js's API); nothing when not embedded. */
export function tellParent(message) {
  if (!state.embedded || window.parent === window) return;
  try {
    window.parent.postMessage(message, "*");
  } catch { /* the embedding page went away */ }
}
