// Loads the WebAssembly viewer and starts it in the page's canvas. The viewer reads
// ?mesh=NAME&autorun=1 itself; failures to load end up in the title, as the contract says.
import init, { start, widgetRect } from './bvseg_viewer.js';

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

try {
  await init();
  // For scripts that click the controls: window.bvseg.widgetRect('Run') -> [x, y, w, h].
  window.bvseg = { widgetRect };
  await start('bvseg-canvas');
  document.getElementById('loading').remove();
} catch (err) {
  fail(err);
}
