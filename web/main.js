// Loads the WebAssembly viewer and starts it in the page's canvas. The viewer reads
// ?mesh=NAME&autorun=1 itself; failures to load end up in the title, as the contract says.
//
// Two builds of the viewer sit side by side (web/build.sh): threads/ runs the core on a pool
// of Web Workers, which needs shared memory, which browsers allow only on a page served
// cross-origin isolated (COOP/COEP headers); the other runs it on the page's own thread.
function fail(err) {
  let msg = String(err && err.message ? err.message : err).split('\n')[0];
  if (err instanceof WebAssembly.CompileError) {
    // The module is built with WebAssembly SIMD (web/build.sh).
    msg += ' (this page needs WebAssembly SIMD: Chrome 91, Firefox 89, Safari 16.4 or later)';
  }
  document.title = `bvseg: error: ${msg}`;
  document.getElementById('bvseg-result').textContent = msg;
  document.getElementById('loading').textContent = `bvseg failed to start: ${msg}`;
}

/** The threaded build when the page may use it and it is there, else the plain one. */
async function load() {
  if (self.crossOriginIsolated) {
    try {
      const viewer = await import('./threads/bvseg_viewer.js');
      await viewer.default();
      // ?threads=N sets the pool's size (for comparisons); all the cores by default.
      const asked = Number(new URLSearchParams(location.search).get('threads'));
      const threads = asked >= 1 ? Math.floor(asked) : Math.max(1, navigator.hardwareConcurrency || 1);
      await viewer.initThreadPool(threads);
      return { viewer, threads };
    } catch (err) {
      console.warn(`bvseg: no threads (${err && err.message ? err.message : err}), running on one`);
    }
  }
  const viewer = await import('./bvseg_viewer.js');
  await viewer.default();
  return { viewer, threads: 1 };
}

/** Whether WebGL runs on a software renderer (no GPU, or a blocked one). */
function softwareGl() {
  const gl = document.createElement('canvas').getContext('webgl2');
  const info = gl && gl.getExtension('WEBGL_debug_renderer_info');
  const name = info ? String(gl.getParameter(info.UNMASKED_RENDERER_WEBGL)) : '';
  return /swiftshader|llvmpipe|softpipe|software/i.test(name);
}

try {
  const software = softwareGl();
  if (software) {
    // A software renderer draws on the CPU, beside the core: without multisampling, a frame
    // of the bundled spot costs about a third less. eframe later asks the canvas for its
    // context and gets this one.
    document.getElementById('bvseg-canvas').getContext('webgl2', { antialias: false });
  }
  const { viewer, threads } = await load();
  // For scripts: window.bvseg.widgetRect('Run') -> [x, y, w, h] to click the controls, and
  // the number of threads the core runs on.
  window.bvseg = { widgetRect: viewer.widgetRect, threads };
  // On a software renderer every frame takes CPU from the core, so the threaded build shows a
  // run's progress less often there.
  await viewer.start('bvseg-canvas', software);
  document.getElementById('loading').remove();
} catch (err) {
  fail(err);
}
