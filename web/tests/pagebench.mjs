// Times the page's run of a bundled mesh, served cross-origin isolated (threads) or plainly,
// alternating, several rounds: `node pagebench.mjs [ROUNDS] [MESH]` after web/build.sh.
import { createServer } from 'node:http';
import { mkdtempSync, readFileSync, rmSync, existsSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, extname, normalize, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';

const here = dirname(fileURLToPath(import.meta.url));
const dist = process.env.BVSEG_DIST || join(here, '..', 'dist');
const rounds = Number(process.argv[2] || 3);
const mesh = process.argv[3] || 'spot';
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
  viewport: { width: 1280, height: 800 },
  deviceScaleFactor: 1,
  args: ['--no-sandbox', '--disable-gpu', '--disable-background-networking',
    '--disable-component-update', '--disable-sync', '--no-first-run', '--enable-unsafe-swiftshader'],
});
const results = { isolated: [], plain: [] };
for (let r = 0; r < rounds; r++) {
  for (const [name, origin] of [['isolated', isolated], ['plain', plain]]) {
    const page = await context.newPage();
    await page.goto(`${origin}/index.html?mesh=${mesh}&autorun=1${process.env.EXTRA || ""}`);
    await page.waitForFunction(() => document.title.startsWith('bvseg: '), null, { timeout: 300_000, polling: 100 });
    const text = await page.locator('#bvseg-result').textContent();
    const threads = await page.evaluate(() => window.bvseg?.threads);
    const j = JSON.parse(text);
    results[name].push(j.time_s);
    console.log(`${name} (${threads} threads): run ${j.time_s.toFixed(2)} s, core ${j.core_s.toFixed(2)} s, ${j.frames} frames, k ${j.k}`);
    await page.close();
  }
}
const median = (a) => [...a].sort((x, y) => x - y)[Math.floor(a.length / 2)];
console.log(`median run: isolated ${median(results.isolated).toFixed(2)} s, plain ${median(results.plain).toFixed(2)} s`);
await context.close();
s1.close();
s2.close();
rmSync(profile, { recursive: true, force: true });
