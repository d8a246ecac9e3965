// Browser test of the web viewer: headless Chromium (Debian's) driven by playwright-core,
// against web/dist served on 127.0.0.1 by a tiny static server. Run `web/test.sh`, or after
// `web/build.sh`: `cd web/tests && npm ci && node --test`.
//
// The page contract: ?mesh=NAME&autorun=1 runs the bundled mesh; the end is signalled by the
// title ("bvseg: done" or "bvseg: error: ...") with the summary JSON in <pre id="bvseg-result">.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { createServer } from 'node:http';
import { mkdtempSync, readFileSync, rmSync, mkdirSync, writeFileSync, existsSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, extname, normalize, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { inflateSync } from 'node:zlib';
import { chromium } from 'playwright-core';

const here = dirname(fileURLToPath(import.meta.url));
const dist = join(here, '..', 'dist');
const shots = join(here, 'screenshots');
const CHROMIUM = process.env.BVSEG_CHROMIUM || '/usr/bin/chromium';
// The mesh of the timed run: a bundled mesh, segmented with the defaults (20,000 samples).
const MESH = process.env.BVSEG_TEST_MESH || 'spot';
const TIMEOUT_MS = 180_000;

const TYPES = {
  '.html': 'text/html; charset=utf-8',
  '.js': 'text/javascript; charset=utf-8',
  '.wasm': 'application/wasm',
};

// The page runs the core on threads only when served cross-origin isolated (web/build.sh).
const ISOLATED = {
  'cross-origin-opener-policy': 'same-origin',
  'cross-origin-embedder-policy': 'require-corp',
};
// Whether web/build.sh made the threaded module (it warns when it could not).
const THREADED = existsSync(join(dist, 'threads', 'bvseg_viewer_bg.wasm'));

let servers = [];
// The page served cross-origin isolated, as it should be, and served plainly.
let base;
let plainBase;
let context;
let profile;

/** A static server of web/dist on 127.0.0.1 sending `headers` with every file; its origin. */
async function serve(headers) {
  const server = createServer((req, res) => {
    const path = normalize(decodeURIComponent(new URL(req.url, 'http://x').pathname));
    const file = join(dist, path === '/' ? 'index.html' : path);
    if (!file.startsWith(dist) || !existsSync(file)) {
      res.writeHead(404).end();
      return;
    }
    res.writeHead(200, { 'content-type': TYPES[extname(file)] || 'application/octet-stream', ...headers });
    res.end(readFileSync(file));
  });
  await new Promise((ok) => server.listen(0, '127.0.0.1', ok));
  servers.push(server);
  return `http://127.0.0.1:${server.address().port}`;
}

before(async () => {
  assert.ok(existsSync(join(dist, 'index.html')), 'web/dist is missing: run web/build.sh first');
  console.log(`# threaded module: ${THREADED ? 'built' : 'absent (web/build.sh warned why)'}`);
  base = await serve(ISOLATED);
  plainBase = await serve({});
  profile = mkdtempSync(join(tmpdir(), 'bvseg-chromium-'));
  // Playwright adds --headless itself (headless: true); the rest keeps Chromium off the
  // network and lets WebGL2 run on SwiftShader without a GPU.
  context = await chromium.launchPersistentContext(profile, {
    executablePath: CHROMIUM,
    headless: true,
    viewport: { width: 1280, height: 800 },
    deviceScaleFactor: 1,
    args: [
      '--no-sandbox',
      '--disable-gpu',
      '--disable-background-networking',
      '--disable-component-update',
      '--disable-sync',
      '--no-first-run',
      '--enable-unsafe-swiftshader',
    ],
  });
});

after(async () => {
  await context?.close();
  for (const server of servers) server.close();
  if (profile) rmSync(profile, { recursive: true, force: true });
});

/** Opens the page with `query` (from `origin`) and waits for the end of the run; returns title,
 * JSON text, and the threads the core ran on. */
async function runPage(query, origin = base) {
  const page = await context.newPage();
  const logs = [];
  page.on('console', (m) => logs.push(`${m.type()}: ${m.text()}`));
  page.on('pageerror', (e) => logs.push(`pageerror: ${e.message}`));
  const t0 = Date.now();
  await page.goto(`${origin}/index.html?${query}`);
  try {
    await page.waitForFunction(
      () => document.title.startsWith('bvseg: done') || document.title.startsWith('bvseg: error'),
      null,
      { timeout: TIMEOUT_MS, polling: 100 },
    );
  } catch (e) {
    throw new Error(`no end of run: title "${await page.title()}"\n${logs.join('\n')}`);
  }
  const seconds = (Date.now() - t0) / 1000;
  const title = await page.title();
  const text = await page.locator('#bvseg-result').textContent();
  const [threads, cores] = await page.evaluate(() => [window.bvseg?.threads, navigator.hardwareConcurrency]);
  return { page, title, text, seconds, logs, threads, cores };
}

/** The threads the page should have run the core on, served from `origin`. */
function expectedThreads(origin, cores) {
  return origin === base && THREADED ? cores : 1;
}

/** Clicks the widget the app says it drew under `label` (eframe's web backend has no
 * accessibility tree), then lets egui take the click in its next frame. */
async function clickWidget(page, label) {
  const r = await page.evaluate((l) => Array.from(window.bvseg.widgetRect(l) || []), label);
  assert.equal(r.length, 4, `no widget "${label}"`);
  await page.mouse.click(r[0] + r[2] / 2, r[1] + r[3] / 2);
  await page.waitForTimeout(300);
}

/** Decodes an 8-bit, non-interlaced RGB or RGBA PNG (what Chromium's screenshots are). */
function decodePng(buf) {
  assert.equal(buf.readUInt32BE(0), 0x89504e47, 'not a PNG');
  let pos = 8;
  let width, height, channels;
  const idat = [];
  while (pos < buf.length) {
    const len = buf.readUInt32BE(pos);
    const type = buf.toString('ascii', pos + 4, pos + 8);
    const data = buf.subarray(pos + 8, pos + 8 + len);
    if (type === 'IHDR') {
      width = data.readUInt32BE(0);
      height = data.readUInt32BE(4);
      assert.equal(data[8], 8, 'bit depth');
      assert.equal(data[12], 0, 'interlace');
      channels = { 2: 3, 6: 4 }[data[9]];
      assert.ok(channels, `colour type ${data[9]}`);
    } else if (type === 'IDAT') {
      idat.push(data);
    }
    pos += 12 + len;
  }
  const raw = inflateSync(Buffer.concat(idat));
  const stride = width * channels;
  const out = Buffer.alloc(width * height * 4);
  const prev = Buffer.alloc(stride);
  const cur = Buffer.alloc(stride);
  for (let y = 0; y < height; y++) {
    const filter = raw[y * (stride + 1)];
    const line = raw.subarray(y * (stride + 1) + 1, (y + 1) * (stride + 1));
    for (let i = 0; i < stride; i++) {
      const a = i >= channels ? cur[i - channels] : 0;
      const b = prev[i];
      const c = i >= channels ? prev[i - channels] : 0;
      let v = line[i];
      if (filter === 1) v += a;
      else if (filter === 2) v += b;
      else if (filter === 3) v += (a + b) >> 1;
      else if (filter === 4) {
        const p = a + b - c;
        const pa = Math.abs(p - a), pb = Math.abs(p - b), pc = Math.abs(p - c);
        v += pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
      }
      cur[i] = v & 255;
    }
    for (let x = 0; x < width; x++) {
      out[(y * width + x) * 4] = cur[x * channels];
      out[(y * width + x) * 4 + 1] = cur[x * channels + 1];
      out[(y * width + x) * 4 + 2] = cur[x * channels + 2];
      out[(y * width + x) * 4 + 3] = channels === 4 ? cur[x * channels + 3] : 255;
    }
    cur.copy(prev);
  }
  return { width, height, data: out };
}

/** Luminance variance and the share of saturated ("mesh-coloured") pixels in a rectangle. */
function pixelStats(img, [x0, y0, w, h]) {
  let n = 0, sum = 0, sum2 = 0, coloured = 0;
  for (let y = Math.max(0, Math.floor(y0)); y < Math.min(img.height, y0 + h); y++) {
    for (let x = Math.max(0, Math.floor(x0)); x < Math.min(img.width, x0 + w); x++) {
      const i = (y * img.width + x) * 4;
      const [r, g, b] = [img.data[i], img.data[i + 1], img.data[i + 2]];
      const l = 0.299 * r + 0.587 * g + 0.114 * b;
      n++;
      sum += l;
      sum2 += l * l;
      // The view's background is a dark blue-grey and egui's widgets are grey: saturated
      // colours there come from the parts' palette on the mesh and the volumes.
      if (Math.max(r, g, b) - Math.min(r, g, b) > 40 && l > 50) coloured++;
    }
  }
  const mean = sum / n;
  return { pixels: n, variance: sum2 / n - mean * mean, coloured: coloured / n };
}

test(`?mesh=${MESH}&autorun=1 segments in the page and draws the result`, async () => {
  const { page, title, text, seconds, logs, threads, cores } = await runPage(`mesh=${MESH}&autorun=1`);
  assert.ok(title.startsWith('bvseg: done'), `title "${title}"\n${logs.join('\n')}`);
  assert.equal(threads, expectedThreads(base, cores), logs.join('\n'));
  const r = JSON.parse(text);
  for (const key of ['tov', 'mov', 'f', 'protrusion', 'protrusion_rel']) {
    assert.ok(Number.isFinite(r[key]), `${key} = ${r[key]}`);
  }
  assert.ok(Number.isInteger(r.k) && r.k >= 2, `k = ${r.k}`);
  assert.ok(r.tov > 0 && r.f >= 1, text);
  assert.ok(r.samples > 15000 && r.samples < 25000, `samples = ${r.samples}`);
  console.log(
    `# ${MESH}: k=${r.k} TOV=${r.tov.toFixed(4)} protrusion=${r.protrusion_rel.toFixed(4)} of the diagonal ` +
      `MOV=${r.mov.toFixed(4)} F=${r.f.toFixed(4)} samples=${r.samples}; tolerances (TOV 0.3, protrusion 0.05) met: ${r.met}; run ${r.time_s.toFixed(2)} s ` +
      `in the page on ${threads} thread(s) (bar 2 s; ${r.core_s.toFixed(2)} s of it in the core, ${r.frames} frames), ` +
      `${seconds.toFixed(2)} s from navigation`,
  );

  mkdirSync(shots, { recursive: true });
  const png = await page.screenshot();
  writeFileSync(join(shots, `${MESH}.png`), png);
  const img = decodePng(png);
  assert.ok(Array.isArray(r.view) && r.view[2] > 100 && r.view[3] > 100, `view ${r.view}`);
  const view = pixelStats(img, r.view);
  console.log(
    `# 3D view ${r.view.map(Math.round).join('x')}: luminance variance ${view.variance.toFixed(1)}, ` +
      `coloured pixels ${(100 * view.coloured).toFixed(1)} %`,
  );
  assert.ok(view.variance > 100, `the 3D view looks blank (variance ${view.variance})`);
  assert.ok(view.coloured > 0.02, `too few mesh-coloured pixels (${view.coloured})`);
  await page.close();
});

for (const [served, origin] of [['cross-origin isolated', () => base], ['plainly', () => plainBase]]) {
  test(`the page's JSON for ${MESH}, served ${served}, is byte-identical to the CLI's`, async () => {
    const cli = join(here, 'cli-json', `${MESH}.json`);
    assert.ok(existsSync(cli), `${cli} is missing: web/test.sh writes it with the CLI`);
    const { page, title, logs, threads, cores } = await runPage(`mesh=${MESH}&autorun=1`, origin());
    assert.ok(title.startsWith('bvseg: done'), `title "${title}"\n${logs.join('\n')}`);
    assert.equal(threads, expectedThreads(origin(), cores), logs.join('\n'));
    const click = (label) => clickWidget(page, label);
    await click('Result');
    const download = page.waitForEvent('download', { timeout: 10_000 });
    await click('Download JSON');
    const file = await (await download).path();
    const fromPage = readFileSync(file);
    const fromCli = readFileSync(cli);
    assert.ok(fromPage.equals(fromCli), `the page's ${fromPage.length} bytes differ from the CLI's ${fromCli.length}`);
    console.log(`# ${MESH}, served ${served}, on ${threads} thread(s): the page's volumes JSON equals the CLI's, ${fromCli.length} bytes`);
    await page.close();
  });
}

test('clicking the controls in the page runs with them', async () => {
  const page = await context.newPage();
  await page.goto(`${base}/index.html?mesh=bunny`);
  // eframe's web backend has no accessibility tree: the app tells where it drew a widget.
  await page.waitForFunction(() => window.bvseg && window.bvseg.widgetRect('Run'), null, {
    timeout: 60_000,
  });
  const click = (label) => clickWidget(page, label);
  // Boxes only: untick the other kinds of the default set.
  for (const kind of ['Ellipsoids', 'Spheres', 'Capsules', 'Cylinders']) await click(kind);
  await click('Fixed k');
  assert.equal(await page.title(), 'bvseg', 'nothing ran yet');
  await click('Run');
  await page.waitForFunction(
    () => document.title.startsWith('bvseg: done') || document.title.startsWith('bvseg: error'),
    null,
    { timeout: TIMEOUT_MS, polling: 100 },
  );
  assert.ok((await page.title()).startsWith('bvseg: done'), await page.title());
  const r = JSON.parse(await page.locator('#bvseg-result').textContent());
  // The run used what was clicked: boxes, and the fixed k of the controls (8).
  assert.equal(r.kind, 'obb');
  assert.equal(r.met, null);
  assert.equal(r.k, 8);
  await page.close();
});

// A box 2 x 1 x 1: eight corners and twelve outward triangles (indices from 0).
const BRICK_V = [0, 1, 2, 3, 4, 5, 6, 7].map((i) => [2 * (i & 1), (i >> 1) & 1, (i >> 2) & 1]);
const BRICK_T = [[0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4], [2, 6, 3],
  [3, 6, 7], [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5]];

function brickObj() {
  const v = BRICK_V.map((p) => `v ${p.join(' ')}`);
  const f = BRICK_T.map((t) => `f ${t.map((i) => i + 1).join(' ')}`);
  return Buffer.from([...v, ...f].join('\n') + '\n');
}

/** Binary STL: every triangle with its own corners (loading welds them). */
function brickStl() {
  const b = Buffer.alloc(84 + 50 * BRICK_T.length);
  b.writeUInt32LE(BRICK_T.length, 80);
  BRICK_T.forEach((t, k) => {
    const at = 84 + 50 * k + 12; // the normal stays zero: readers recompute it
    t.forEach((i, j) => BRICK_V[i].forEach((c, a) => b.writeFloatLE(c, at + 12 * j + 4 * a)));
  });
  return b;
}

/** Binary glTF: one indexed primitive. */
function brickGlb() {
  const pos = Buffer.alloc(12 * BRICK_V.length);
  BRICK_V.flat().forEach((c, i) => pos.writeFloatLE(c, 4 * i));
  const idx = Buffer.alloc(4 * 3 * BRICK_T.length);
  BRICK_T.flat().forEach((v, i) => idx.writeUInt32LE(v, 4 * i));
  const bin = Buffer.concat([pos, idx]);
  let json = Buffer.from(JSON.stringify({
    asset: { version: '2.0' },
    scene: 0, scenes: [{ nodes: [0] }], nodes: [{ mesh: 0 }],
    meshes: [{ primitives: [{ attributes: { POSITION: 0 }, indices: 1 }] }],
    accessors: [
      { bufferView: 0, componentType: 5126, count: BRICK_V.length, type: 'VEC3', min: [0, 0, 0], max: [2, 1, 1] },
      { bufferView: 1, componentType: 5125, count: 3 * BRICK_T.length, type: 'SCALAR' },
    ],
    bufferViews: [
      { buffer: 0, byteOffset: 0, byteLength: pos.length },
      { buffer: 0, byteOffset: pos.length, byteLength: idx.length },
    ],
    buffers: [{ byteLength: bin.length }],
  }));
  json = Buffer.concat([json, Buffer.alloc((4 - (json.length % 4)) % 4, 0x20)]);
  const header = Buffer.alloc(12);
  header.write('glTF', 0);
  header.writeUInt32LE(2, 4);
  header.writeUInt32LE(12 + 8 + json.length + 8 + bin.length, 8);
  const chunk = (data, type) => {
    const h = Buffer.alloc(8);
    h.writeUInt32LE(data.length, 0);
    h.write(type, 4, 'latin1');
    return Buffer.concat([h, data]);
  };
  return Buffer.concat([header, chunk(json, 'JSON'), chunk(bin, 'BIN\0')]);
}

for (const [name, bytes] of [['brick.obj', brickObj], ['brick.glb', brickGlb], ['brick.stl', brickStl]]) {
  test(`${name} opened through the file dialog is what runs`, async () => {
    const dir = mkdtempSync(join(tmpdir(), 'bvseg-open-'));
    const file = join(dir, name);
    writeFileSync(file, bytes());
    const page = await context.newPage();
    await page.goto(`${base}/index.html`);
    await page.waitForFunction(() => window.bvseg && window.bvseg.widgetRect('Mesh'), null, {
      timeout: 60_000,
    });
    const click = (label) => clickWidget(page, label);
    await click('Mesh');
    const chooser = page.waitForEvent('filechooser', { timeout: 10_000 });
    await click('Open file…');
    const fc = await chooser;
    // The dialog offers every format the viewer reads.
    const accept = await fc.element().getAttribute('accept');
    for (const ext of ['.obj', '.gltf', '.glb', '.stl']) {
      assert.ok(accept.split(',').map((a) => a.trim()).includes(ext), `accept="${accept}"`);
    }
    await fc.setFiles(file);
    await page.waitForTimeout(500);
    for (const kind of ['Ellipsoids', 'Spheres', 'Capsules', 'Cylinders']) await click(kind);
    await click('Fixed k');
    await click('Run');
    await page.waitForFunction(
      () => document.title.startsWith('bvseg: done') || document.title.startsWith('bvseg: error'),
      null,
      { timeout: TIMEOUT_MS, polling: 100 },
    );
    assert.ok((await page.title()).startsWith('bvseg: done'), await page.title());
    const r = JSON.parse(await page.locator('#bvseg-result').textContent());
    assert.equal(r.mesh, name);
    assert.equal(r.kind, 'obb');
    assert.equal(r.k, 8);
    // Boxes around the parts of a box: little outside volume.
    assert.ok(Number.isFinite(r.tov) && r.tov < 1, `TOV ${r.tov}`);
    console.log(`# ${name}, 8 boxes: TOV ${r.tov.toFixed(4)}`);
    await page.close();
    rmSync(dir, { recursive: true, force: true });
  });
}

/** The share of pixels of rectangle `r` that differ clearly between two decoded screenshots. */
function changedShare(a, b, [x0, y0, w, h]) {
  let n = 0, changed = 0;
  for (let y = Math.max(0, Math.floor(y0)); y < Math.min(a.height, y0 + h); y++) {
    for (let x = Math.max(0, Math.floor(x0)); x < Math.min(a.width, x0 + w); x++) {
      const i = (y * a.width + x) * 4;
      n++;
      if ([0, 1, 2].some((c) => Math.abs(a.data[i + c] - b.data[i + c]) > 30)) changed++;
    }
  }
  return changed / n;
}

test('a character opened through the file dialog walks in the page with its volumes', async () => {
  const glb = join(here, '..', '..', 'assets', 'characters', 'CesiumMan.glb');
  const page = await context.newPage();
  await page.goto(`${base}/index.html`);
  await page.waitForFunction(() => window.bvseg && window.bvseg.widgetRect('Mesh'), null, {
    timeout: 60_000,
  });
  const click = (label) => clickWidget(page, label);
  await click('Mesh');
  const chooser = page.waitForEvent('filechooser', { timeout: 10_000 });
  await click('Open file…');
  await (await chooser).setFiles(glb);
  // A mesh with an animation gets the animation controls.
  await page.waitForFunction(() => window.bvseg.widgetRect('Play'), null, { timeout: 30_000 });
  await click('Run');
  await page.waitForFunction(
    () => document.title.startsWith('bvseg: done') || document.title.startsWith('bvseg: error'),
    null,
    { timeout: TIMEOUT_MS, polling: 100 },
  );
  assert.ok((await page.title()).startsWith('bvseg: done'), await page.title());
  const r = JSON.parse(await page.locator('#bvseg-result').textContent());
  assert.equal(r.mesh, 'CesiumMan.glb');
  assert.ok(r.k >= 2, `k = ${r.k}`);
  const shot = async () => decodePng(await page.screenshot());
  const rest = await shot();
  await click('Play');
  await page.waitForTimeout(1000);
  const walking = await shot();
  await click('Pause');
  const paused = await shot();
  await page.waitForTimeout(500);
  const still = await shot();
  mkdirSync(shots, { recursive: true });
  writeFileSync(join(shots, 'CesiumMan-walking.png'), await page.screenshot());
  const moved = changedShare(rest, walking, r.view);
  const drift = changedShare(paused, still, r.view);
  console.log(
    `# CesiumMan.glb: k=${r.k}, run ${r.time_s.toFixed(2)} s; after a second of play ` +
      `${(100 * moved).toFixed(2)} % of the view changed, paused ${(100 * drift).toFixed(3)} %`,
  );
  assert.ok(moved > 0.002, `the view did not change while playing (${moved})`);
  assert.ok(drift < 0.0005, `the view changed while paused (${drift})`);
  await page.close();
});

test('an unknown mesh name ends in "bvseg: error"', async () => {
  const { page, title, text } = await runPage('mesh=no-such-mesh&autorun=1');
  assert.ok(title.startsWith('bvseg: error'), title);
  assert.match(text, /no-such-mesh/);
  await page.close();
});
