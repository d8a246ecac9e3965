// Times the page's run of a bundled mesh, served cross-origin isolated (threads) or plainly,
// alternating, several rounds: `node pagebench.mjs [ROUNDS] [MESH]` after web/build.sh.
// Environment: BVSEG_DIST (the build to serve, default ../dist), PAGES=isolated or plain (only
// that one), EXTRA (appended to the query, e.g. `&threads=1`), JSFLAGS (V8 flags, e.g.
// `--liftoff-only`), CPU=1 (print the browser's CPU time per thread name over each page's
// run (and each later run's), from /proc: the core's workers are `DedicatedWorker`, V8's background compilation
// `ThreadPoolForeg...`, SwiftShader's drawing `Thread<NN>`), AGAIN=N (then click Run N more
// times on the same page and print those runs too, and their median last: the browser has
// compiled the module by then), CLICK=S (load the page without autorun, wait S seconds once its
// Run button is drawn, as a user would, then click Run and time that run). Each run prints
// its core time (the figure the medians take) and when the page showed its result: that many
// seconds after the click, or after the navigation for a first run with autorun. VIEW=WxH
// sets the page's size in CSS pixels (default 1280x800): on a software renderer a frame's
// cost grows with its pixels, so a small page shows what the drawing costs the run.
import { createServer } from 'node:http';
import { mkdtempSync, readFileSync, readdirSync, rmSync, existsSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, extname, normalize, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';

const here = dirname(fileURLToPath(import.meta.url));
const dist = process.env.BVSEG_DIST || join(here, '..', 'dist');
const rounds = Number(process.argv[2] || 3);
const mesh = process.argv[3] || 'spot';
const pages = process.env.PAGES ? process.env.PAGES.split(',') : ['isolated', 'plain'];
const view = (process.env.VIEW || '1280x800').split('x').map(Number);
if (view.length !== 2 || !view.every((n) => Number.isInteger(n) && n > 0)) {
  throw new Error(`VIEW=${process.env.VIEW}: give the page's size as WIDTHxHEIGHT, e.g. 640x400`);
}

/** CPU time (clock ticks) of each thread of the browser's processes, by `pid/tid`. */
function browserThreads() {
  const out = new Map();
  for (const pid of readdirSync('/proc').filter((d) => /^\d+$/.test(d))) {
    try {
      if (!readFileSync(`/proc/${pid}/cmdline`, 'latin1').split('\0')[0].includes('chrom')) continue;
      for (const tid of readdirSync(`/proc/${pid}/task`)) {
        const st = readFileSync(`/proc/${pid}/task/${tid}/stat`, 'latin1');
        const name = st.slice(st.indexOf('(') + 1, st.lastIndexOf(')'));
        const f = st.slice(st.lastIndexOf(')') + 2).split(' ');
        out.set(`${pid}/${tid}`, [name, Number(f[11]) + Number(f[12])]);
      }
    } catch {
      // The process or thread ended meanwhile.
    }
  }
  return out;
}

/** Seconds of CPU per thread name between two `browserThreads()` (clock ticks of 10 ms). */
function cpuSince(before, after) {
  const by = new Map();
  for (const [key, [name, ticks]] of after) {
    const d = ticks - (before.get(key)?.[1] ?? 0);
    if (d > 0) by.set(name, (by.get(name) ?? 0) + d);
  }
  return [...by].sort((a, b) => b[1] - a[1]).slice(0, 6)
    .map(([name, d]) => `${name} ${(d / 100).toFixed(2)}`).join(', ');
}

const TYPES = { '.html': 'text/html', '.js': 'text/javascript', '.wasm': 'application/wasm' };

async function serve(headers) {
  const server = createServer((req, res) => {
    const path = normalize(decodeURIComponent(new URL(req.url, 'http://x').pathname));
    const file = join(dist, path === '/' ? 'index.html' : path);
    if (!file.startsWith(dist) || !existsSync(file)) return res.writeHead(404).end();
    res.writeHead(200, { 'content-type': TYPES[extname(file)] || 'application/octet-stream', ...headers });
    res.end(readFileSync(file));
  });
  await new Promise((ok) => server.listen(0, '127.0.0.1', ok));
  return [server, `http://127.0.0.1:${server.address().port}`];
}

const [s1, isolated] = await serve({
  'cross-origin-opener-policy': 'same-origin',
  'cross-origin-embedder-policy': 'require-corp',
});
const [s2, plain] = await serve({});
const profile = mkdtempSync(join(tmpdir(), 'bvseg-bench-'));
const context = await chromium.launchPersistentContext(profile, {
  executablePath: process.env.BVSEG_CHROMIUM || '/usr/bin/chromium',
  headless: true,
  viewport: { width: view[0], height: view[1] },
  deviceScaleFactor: 1,
  args: ['--no-sandbox', '--disable-gpu', '--disable-background-networking',
    '--disable-component-update', '--disable-sync', '--no-first-run', '--enable-unsafe-swiftshader',
    ...(process.env.JSFLAGS ? [`--js-flags=${process.env.JSFLAGS}`] : [])],
});
// When the page shows a run's end (its title changes) and when a click last ended (pointer up,
// when egui takes the click), on the page's clock: what the user waits, from the click or from
// the page's navigation (autorun), to the result on the screen.
await context.addInitScript(() => {
  addEventListener('pointerup', () => { window.__clickAt = performance.now(); }, true);
  new MutationObserver(() => {
    if (document.title.startsWith('bvseg: ')) window.__shownAt ??= performance.now();
  }).observe(document, { subtree: true, childList: true, characterData: true });
});
/** Seconds from the last click (or, with none, the navigation) to the result on the screen. */
async function shown(page) {
  return page.evaluate(() => (window.__shownAt - (window.__clickAt ?? 0)) / 1000);
}
/** Waits for the end of the page's run and returns its summary. */
async function result(page) {
  await page.waitForFunction(() => document.title.startsWith('bvseg: '), null, { timeout: 300_000, polling: 100 });
  return JSON.parse(await page.locator('#bvseg-result').textContent());
}
/** Clicks the page's Run button. */
async function clickRun(page) {
  const rect = await page.evaluate(() => Array.from(window.bvseg.widgetRect('Run') || []));
  await page.mouse.click(rect[0] + rect[2] / 2, rect[1] + rect[3] / 2);
}
const figures = (j, seen, click) => `${j.time_s.toFixed(2)} s, core ${j.core_s.toFixed(2)} s, ${j.frames} frames, k ${j.k}; shown ${seen.toFixed(2)} s after the ${click ? 'click' : 'navigation'}`;

const results = { isolated: [], plain: [] };
// Runs after the first on the same page (AGAIN): the browser has compiled the module by then.
const later = { isolated: [], plain: [] };
// From the click to the result on the screen, for runs started by a click.
const seen = { isolated: [], plain: [] };
const served = [['isolated', isolated], ['plain', plain]].filter(([name]) => pages.includes(name));
for (let round = 0; round < rounds; round++) {
  for (const [name, origin] of served) {
    const page = await context.newPage();
    const before = process.env.CPU ? browserThreads() : null;
    const click = process.env.CLICK !== undefined;
    await page.goto(`${origin}/index.html?mesh=${mesh}${click ? '' : '&autorun=1'}${process.env.EXTRA || ""}`);
    if (click) {
      await page.waitForFunction(() => window.bvseg?.widgetRect('Run'), null, { timeout: 60_000, polling: 50 });
      await page.waitForTimeout(1000 * Number(process.env.CLICK));
      await clickRun(page);
    }
    const j = await result(page);
    if (before) console.log(`  CPU (s): ${cpuSince(before, browserThreads())}`);
    const threads = await page.evaluate(() => window.bvseg?.threads);
    results[name].push(j.time_s);
    const s1seen = await shown(page);
    if (click) seen[name].push(s1seen);
    console.log(`${name} (${threads} threads): run ${figures(j, s1seen, click)}`);
    for (let again = 1; again <= Number(process.env.AGAIN || 0); again++) {
      await page.evaluate(() => { document.title = 'bvseg'; window.__shownAt = undefined; });
      const before2 = process.env.CPU ? browserThreads() : null;
      await clickRun(page);
      const j2 = await result(page);
      later[name].push(j2.time_s);
      const s2seen = await shown(page);
      seen[name].push(s2seen);
      if (before2) console.log(`  CPU (s): ${cpuSince(before2, browserThreads())}`);
      console.log(`  run ${again + 1} on the same page: ${figures(j2, s2seen, true)}`);
    }
    await page.close();
  }
}
const median = (a) => [...a].sort((x, y) => x - y)[Math.floor(a.length / 2)];
/** `label: isolated X s, plain Y s`, the medians of `times` (scripts/benchmarks.py reads it). */
const medians = (label, times) =>
  console.log(`${label}: ${pages.map((p) => `${p} ${median(times[p]).toFixed(2)} s`).join(', ')}`);
medians('median run', results);
if (later[pages[0]].length) medians('median later run', later);
if (seen[pages[0]].length) medians('median click to result shown', seen);
await context.close();
s1.close();
s2.close();
rmSync(profile, { recursive: true, force: true });
