// One thread of the computing worker's pool (the threaded module, pkg/threads/). The page
// starts one per thread when the computing worker reports its pool (main.js) and terminates
// them together with it on Cancel, so no thread outlives a cancelled run. It joins the
// module's shared memory and then runs one of rayon's threads for good (src/wasm.rs,
// "thread pool").
//
//   page → { module: WebAssembly.Module, memory: WebAssembly.Memory (shared) }
//   ← { type: "started" } once joined (then busy for good), or { type: "failed", message }

/** Stack of each pool thread, bytes: rayon's default for native threads (2 MiB). */
const THREAD_STACK_BYTES = 2 * 1024 * 1024;

self.onmessage = async ({ data }) => {
  let mod;
  try {
    mod = await import("../pkg/threads/weft.js");
    mod.initSync({ module: data.module, memory: data.memory, thread_stack_size: THREAD_STACK_BYTES });
  } catch (err) {
    self.postMessage({ type: "failed", message: String(err?.message ?? err) });
    return;
  }
  self.postMessage({ type: "started" });
  try {
    mod.runPoolThread(); // returns only if the pool ends
  } catch (err) {
    // A panic or trap on this thread: the computing worker would wait for it for ever, so
    // the page replaces them all.
    self.postMessage({ type: "failed", message: String(err?.message ?? err) });
  }
};
