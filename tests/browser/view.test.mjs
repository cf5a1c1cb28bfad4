// The pages of `symcorr view` in a real browser: headless Chromium (Debian's `chromium`) driven
// with playwright-core. The test makes its pages with the `symcorr` binary of the Cargo target
// folder (`$CARGO_TARGET_DIR` or ./target, debug profile: `cargo build -p symcorr` first), then
// for each view waits for the page to say it is ready, takes screenshots into
// tests/browser/out/screens/ and checks what is drawn, what a click picks and the console.
// Every glTF file those commands wrote also goes through the Khronos glTF validator.
//
// Run: `npm ci && node --test` in this folder (`.ci/run` does).

import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import zlib from 'node:zlib';
import { fileURLToPath, pathToFileURL } from 'node:url';
import { chromium } from 'playwright-core';
import gltfValidator from 'gltf-validator';

const here = path.dirname(fileURLToPath(import.meta.url));
const repo = path.resolve(here, '../..');
const targetDir = path.resolve(repo, process.env.CARGO_TARGET_DIR || 'target');
const bin = path.join(targetDir, 'debug', 'symcorr');
const out = path.join(here, 'out');
const screens = path.join(out, 'screens');
const bodies = path.join(repo, 'fixtures/synth/bodies');
const recording = path.join(repo, 'fixtures/synth/recording');
const WIDTH = 1280;
const HEIGHT = 720;

// The 17-segment palette's most distinctive left/right twins (symcorr-attach's palette).
const TWINS = {
  upper_arm_left: [245, 130, 48], upper_arm_right: [70, 240, 240],
  forearm_left: [255, 225, 25], forearm_right: [145, 30, 180],
  thigh_left: [128, 0, 0], thigh_right: [0, 0, 128],
  shin_left: [170, 110, 40], shin_right: [0, 100, 0],
};

function symcorr(...args) {
  return execFileSync(bin, args, { cwd: repo, encoding: 'utf8', stdio: ['ignore', 'pipe', 'inherit'] });
}

let browser;
let userDir;
const pages = {};

before(async () => {
  assert.ok(fs.existsSync(bin), `${bin} missing: build it first (cargo build -p symcorr)`);
  fs.rmSync(out, { recursive: true, force: true });
  fs.mkdirSync(screens, { recursive: true });
  // The demo writes its pair page (with the dataset's ground truth) beside its results.
  symcorr('demo', '--out', path.join(out, 'demo'));
  pages.pair = path.join(out, 'demo', 'view.html');
  // A labels page.
  const mesh = path.join(bodies, 'meshes', 's1_walk-10.ply');
  symcorr('label', mesh, '--joints', path.join(bodies, 'joints', 's1_walk-10.json'), '--out', path.join(out, 'labels.json'),
    '--glb', path.join(out, 'labels.glb'));
  pages.labels = path.join(out, 'labels.html');
  symcorr('view', path.join(out, 'labels.json'), mesh, '--out', pages.labels);
  // A track page of the first frames of the synthetic recording.
  // `track --view` writes the same page as `view DIR`.
  pages.track = path.join(out, 'track.html');
  symcorr('track', recording, '--joints', path.join(recording, 'joints.json'), '--out', path.join(out, 'track'), '--frames', '0..4',
    '--view', pages.track);
  symcorr('view', path.join(out, 'track'), '--out', path.join(out, 'track-again.html'));
  assert.ok(fs.readFileSync(pages.track).equals(fs.readFileSync(path.join(out, 'track-again.html'))), 'track --view = view DIR');

  // A single-view scan of a body, matched densely, with `match --view`: a partial target.
  const scan = path.join(repo, 'fixtures/synth/scan');
  symcorr('scan', '--depth', path.join(scan, 'depth.png'), '--intrinsics', path.join(scan, 'intrinsics.json'),
    '--joints', path.join(scan, 'joints.json'), '--out', path.join(out, 'scan.ply'));
  pages.partial = path.join(out, 'partial.html');
  symcorr('match', path.join(bodies, 'meshes', 's0_rest.ply'), path.join(out, 'scan.ply'),
    '--template-joints', path.join(bodies, 'joints', 's0_rest.json'), '--target-joints', path.join(scan, 'joints.json'),
    '--dense', '--out', path.join(out, 'partial.json'), '--view', pages.partial);

  userDir = fs.mkdtempSync(path.join(os.tmpdir(), 'symcorr-chromium-'));
  browser = await chromium.launchPersistentContext(userDir, {
    executablePath: '/usr/bin/chromium',
    headless: true,
    viewport: { width: WIDTH, height: HEIGHT },
    deviceScaleFactor: 1,
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
      '--disable-background-networking', '--disable-component-update', '--disable-sync',
      '--use-angle=swiftshader', '--enable-unsafe-swiftshader'],
  });
});

after(async () => {
  if (browser) await browser.close();
  if (userDir) fs.rmSync(userDir, { recursive: true, force: true });
});

// Opens a page file, waits until it reports ready; returns the page, its console errors and
// how long it took to show its first frame.
async function open(file) {
  const page = await browser.newPage();
  const errors = [];
  const requests = [];
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('request', (r) => { if (!r.url().startsWith('file:') && !r.url().startsWith('data:')) requests.push(r.url()); });
  await page.goto(pathToFileURL(file).href);
  await page.waitForFunction(() => window.symcorrView && (window.symcorrView.ready || window.symcorrView.error),
    null, { timeout: 120000 });
  const state = await page.evaluate(() => ({ error: window.symcorrView.error, loadMs: window.symcorrView.loadMs }));
  assert.equal(state.error, null, 'the page reports no error');
  const bytes = fs.statSync(file).size;
  console.log(`${path.relative(repo, file)}: ${(bytes / 1e6).toFixed(2)} MB, first frame after ${Math.round(state.loadMs)} ms`);
  return { page, errors, requests };
}

// Two animation frames, so that what was changed is drawn.
async function settle(page) {
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
}

async function shot(page, name) {
  await settle(page);
  const file = path.join(screens, `${name}.png`);
  const buf = await page.screenshot({ path: file });
  return decodePng(buf);
}

// A PNG (8-bit RGB or RGBA, what Chromium writes) decoded with node's zlib.
function decodePng(buf) {
  let pos = 8, w = 0, h = 0, depth = 0, type = 0;
  const idat = [];
  while (pos < buf.length) {
    const len = buf.readUInt32BE(pos);
    const kind = buf.toString('ascii', pos + 4, pos + 8);
    const data = buf.subarray(pos + 8, pos + 8 + len);
    if (kind === 'IHDR') { w = data.readUInt32BE(0); h = data.readUInt32BE(4); depth = data[8]; type = data[9]; }
    else if (kind === 'IDAT') idat.push(data);
    else if (kind === 'IEND') break;
    pos += 12 + len;
  }
  assert.ok(depth === 8 && (type === 6 || type === 2), `PNG of depth ${depth}, colour type ${type}`);
  const bpp = type === 6 ? 4 : 3, stride = w * bpp;
  const raw = zlib.inflateSync(Buffer.concat(idat));
  const px = Buffer.alloc(h * stride);
  for (let y = 0; y < h; y++) {
    const filter = raw[y * (stride + 1)];
    const src = raw.subarray(y * (stride + 1) + 1, (y + 1) * (stride + 1));
    const row = px.subarray(y * stride, (y + 1) * stride);
    const prev = y > 0 ? px.subarray((y - 1) * stride, y * stride) : null;
    for (let i = 0; i < stride; i++) {
      const a = i >= bpp ? row[i - bpp] : 0, b = prev ? prev[i] : 0, c = prev && i >= bpp ? prev[i - bpp] : 0;
      let v = src[i];
      if (filter === 1) v += a;
      else if (filter === 2) v += b;
      else if (filter === 3) v += (a + b) >> 1;
      else if (filter === 4) {
        const p = a + b - c, pa = Math.abs(p - a), pb = Math.abs(p - b), pc = Math.abs(p - c);
        v += pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
      }
      row[i] = v & 255;
    }
  }
  return { w, h, at: (x, y) => { const i = (y * w + x) * bpp; return [px[i], px[i + 1], px[i + 2]]; } };
}

// The middle of a rectangle, clear of the panels in its corners.
function middle(r) {
  return { x0: Math.round(r.x + 0.15 * r.w), x1: Math.round(r.x + 0.85 * r.w), y0: Math.round(r.y + 0.2 * r.h), y1: Math.round(r.y + 0.8 * r.h) };
}

// Fraction of pixels of a region that are not the white background.
function drawnFraction(img, region) {
  let drawn = 0, all = 0;
  for (let y = region.y0; y < region.y1; y++) {
    for (let x = region.x0; x < region.x1; x++) {
      const [r, g, b] = img.at(x, y);
      if (r < 245 || g < 245 || b < 245) drawn++;
      all++;
    }
  }
  return drawn / all;
}

// Of the drawn pixels of a region, the fraction that are grey (no hue).
function greyFraction(img, region) {
  let grey = 0, drawn = 0;
  for (let y = region.y0; y < region.y1; y++) {
    for (let x = region.x0; x < region.x1; x++) {
      const c = img.at(x, y);
      if (Math.min(...c) >= 245) continue;
      drawn++;
      if (Math.max(...c) - Math.min(...c) <= 12) grey++;
    }
  }
  return drawn ? grey / drawn : 0;
}

// Pixels of a region whose colour is `rgb` up to shading (white light scales all channels).
function countColour(img, region, rgb, tol = 0.1) {
  const m = Math.max(...rgb);
  const want = rgb.map((c) => c / m);
  let n = 0;
  for (let y = region.y0; y < region.y1; y++) {
    for (let x = region.x0; x < region.x1; x++) {
      const c = img.at(x, y);
      const cm = Math.max(...c);
      if (cm < 25 || Math.min(...c) > 235) continue;
      if (c.every((v, k) => Math.abs(v / cm - want[k]) <= tol)) n++;
    }
  }
  return n;
}

function assertTwinColours(img, region, where) {
  const counts = Object.fromEntries(Object.entries(TWINS).map(([name, rgb]) => [name, countColour(img, region, rgb)]));
  for (const side of ['thigh', 'upper_arm']) {
    assert.ok(counts[`${side}_left`] >= 20, `${where}: ${side}_left's colour drawn (${JSON.stringify(counts)})`);
    assert.ok(counts[`${side}_right`] >= 20, `${where}: ${side}_right's colour drawn (${JSON.stringify(counts)})`);
  }
  const present = Object.values(counts).filter((n) => n >= 20).length;
  assert.ok(present >= 6, `${where}: ${present} of the 8 twin colours drawn (${JSON.stringify(counts)})`);
}

// The first of `vertices` that the page shows unhidden inside its view `name`.
// The first of `vertices` that is in view and that the page itself picks at the whole pixel
// nearest its projection: a click there must select exactly it, not a neighbour.
async function visibleVertex(page, name, vertices) {
  return page.evaluate(([name, vertices]) => {
    for (const v of vertices) {
      const p = window.symcorrView.project(name, v);
      if (!p || !p.visible || !p.inside) continue;
      const [x, y] = [Math.round(p.x), Math.round(p.y)];
      if (window.symcorrView.pick(name, x, y) === v) return { v, x, y };
    }
    return null;
  }, [name, vertices]);
}

// Whether a pixel near (x, y) has the colour `rgb` exactly enough (an unlit marker).
function markerNear(img, x, y, rgb) {
  for (let dy = -3; dy <= 3; dy++) {
    for (let dx = -3; dx <= 3; dx++) {
      const c = img.at(Math.round(x) + dx, Math.round(y) + dy);
      if (c.every((v, k) => Math.abs(v - rgb[k]) <= 40)) return true;
    }
  }
  return false;
}

test('pair view: both bodies, segment colours, a click shows the match and its truth', async () => {
  const { page, errors, requests } = await open(pages.pair);
  const views = await page.evaluate(() => window.symcorrView.views);
  assert.deepEqual(views.map((v) => v.name), ['template', 'target']);
  const [left, right] = views.map((v) => middle(v.rect));
  assert.ok(left.x1 <= WIDTH / 2 + 1 && right.x0 >= WIDTH / 2 - 1, 'side by side');

  const transfer = await shot(page, 'pair-transfer');
  assert.ok(drawnFraction(transfer, left) > 0.05, 'the template is drawn');
  assert.ok(drawnFraction(transfer, right) > 0.05, 'the target is drawn');
  assert.equal(countColour(transfer, left, TWINS.thigh_left, 0.03) + countColour(transfer, left, TWINS.thigh_right, 0.03) < 400, true,
    'colour transfer is not the segment palette');

  const modes = await page.evaluate(() => window.symcorrView.modes);
  assert.deepEqual(modes, ['transfer', 'segments', 'confidence', 'error']);
  await page.evaluate(() => window.symcorrView.setMode('segments'));
  const segments = await shot(page, 'pair-segments');
  assertTwinColours(segments, left, 'template');
  assertTwinColours(segments, right, 'target');
  assert.ok(await page.isVisible('#legend'), 'the segment legend is shown');
  assert.equal(await page.locator('#legend div').count(), 17);

  // Click a template vertex that the correspondence file matches, and is in view.
  const corr = JSON.parse(fs.readFileSync(path.join(out, 'demo', 'correspondence.json'), 'utf8'));
  const match = new Map();
  for (const [p, q] of corr.pairs) if (!match.has(p)) match.set(p, q);
  const candidates = [...match.keys()].filter((_, i) => i % 7 === 0).slice(0, 150);
  const hit = await visibleVertex(page, 'template', candidates);
  assert.ok(hit, 'some matched template vertex is in view');
  await page.mouse.click(hit.x, hit.y);
  await settle(page);
  const sel = await page.evaluate(() => window.symcorrView.selected);
  assert.equal(sel.template, hit.v, 'the click picks the vertex under the cursor');
  assert.equal(sel.matchedTemplate, hit.v);
  assert.equal(sel.target, match.get(hit.v), 'its match is the file\'s');
  // The demo's bodies share one vertex order: the true point is the same id.
  assert.equal(sel.truth, hit.v);
  assert.ok(Number.isFinite(sel.error) && sel.error >= 0, `geodesic error ${sel.error}`);
  const info = await page.textContent('#info');
  assert.match(info, new RegExp(`target ${sel.target} `));
  assert.match(info, /geodesic error/);
  const selected = await shot(page, 'pair-selected');
  const at = await page.evaluate((q) => window.symcorrView.project('target', q), sel.target);
  assert.ok(markerNear(selected, at.x, at.y, [0, 255, 0]), 'the match is marked on the target');
  const t = await page.evaluate(() => window.symcorrView.project('template', window.symcorrView.selected.template));
  assert.ok(markerNear(selected, t.x, t.y, [255, 32, 32]), 'the point is marked on the template');

  await page.evaluate(() => window.symcorrView.setMode('error'));
  const heat = await shot(page, 'pair-error');
  assert.ok(drawnFraction(heat, left) > 0.05 && drawnFraction(heat, right) > 0.05);
  await page.evaluate(() => window.symcorrView.setMode('confidence'));
  await shot(page, 'pair-confidence');

  assert.deepEqual(errors, [], 'no console errors');
  assert.deepEqual(requests, [], 'nothing fetched from the network');
  await page.close();
});

test('labels view: segments, joints and bones; a click names the segment', async () => {
  const { page, errors, requests } = await open(pages.labels);
  const state = await page.evaluate(() => ({ views: window.symcorrView.views, joints: window.symcorrView.joints, bones: window.symcorrView.bones }));
  const labels = JSON.parse(fs.readFileSync(path.join(out, 'labels.json'), 'utf8'));
  assert.equal(state.joints, Object.keys(labels.joints).length);
  assert.ok(state.bones >= 15, `${state.bones} bones drawn`);
  const region = middle(state.views[0].rect);
  const img = await shot(page, 'labels');
  assert.ok(drawnFraction(img, region) > 0.05, 'the body is drawn');
  assertTwinColours(img, region, 'labels');
  // The skeleton's dark rods and balls are drawn over the body.
  let dark = 0;
  for (let y = region.y0; y < region.y1; y++) for (let x = region.x0; x < region.x1; x++) if (Math.max(...img.at(x, y)) < 70) dark++;
  assert.ok(dark > 200, `${dark} skeleton pixels`);

  const candidates = [];
  for (let v = 0; v < labels.labels.length; v += 97) if (labels.labels[v] !== null) candidates.push(v);
  const hit = await visibleVertex(page, 'mesh', candidates);
  assert.ok(hit);
  await page.mouse.click(hit.x, hit.y);
  const sel = await page.evaluate(() => window.symcorrView.selected);
  assert.equal(sel.vertex, hit.v);
  assert.equal(sel.segment, labels.segments[labels.labels[hit.v]]);
  assert.match(await page.textContent('#info'), new RegExp(sel.segment));
  await shot(page, 'labels-selected');
  assert.deepEqual(errors, []);
  assert.deepEqual(requests, []);
  await page.close();
});

test('track view: the template follows the frames, with each frame\'s status', async () => {
  const { page, errors, requests } = await open(pages.track);
  const track = JSON.parse(fs.readFileSync(path.join(out, 'track', 'track.json'), 'utf8'));
  const frames = track.frames;
  const state = await page.evaluate(() => ({ frames: window.symcorrView.frames, frame: window.symcorrView.frame, views: window.symcorrView.views }));
  assert.equal(state.frames, frames.length);
  assert.equal(await page.locator('#strip div').count(), frames.length);
  const region = middle(state.views[0].rect);
  const posedFrames = frames.map((f, i) => [f, i]).filter(([f]) => f.posed === true).map(([, i]) => i);
  assert.ok(posedFrames.length >= 2, `${posedFrames.length} posed frames`);
  const positions = [];
  for (const i of [posedFrames[0], posedFrames[posedFrames.length - 1]]) {
    await page.evaluate((i) => window.symcorrView.setFrame(i), i);
    const img = await shot(page, `track-frame-${frames[i].frame}`);
    assert.ok(drawnFraction(img, region) > 0.02, `frame ${frames[i].frame} is drawn`);
    const status = await page.textContent('#frame-status');
    assert.ok(status.startsWith(frames[i].status), `status line ${status}`);
    for (const c of frames[i].corrections || []) assert.ok(status.includes(c), `${c} shown`);
    positions.push(await page.evaluate(() => window.symcorrView.project('mesh', 0)));
  }
  assert.notDeepEqual(positions[0], positions[1], 'the template moves between frames');
  // Play runs to the last frame and stops.
  await page.evaluate(() => { window.symcorrView.setFrame(0); window.symcorrView.play(); });
  await page.waitForFunction((last) => window.symcorrView.frame === last && !window.symcorrView.playing, frames.length - 1, { timeout: 60000 });
  await shot(page, 'track-played');
  assert.deepEqual(errors, []);
  assert.deepEqual(requests, []);
  await page.close();
});

test('pair view of a partial scan: template points the scan does not show are grey', async () => {
  const { page, errors, requests } = await open(pages.partial);
  const corr = JSON.parse(fs.readFileSync(path.join(out, 'partial.json'), 'utf8'));
  assert.ok(corr.no_counterpart.length > 100, `${corr.no_counterpart.length} unseen points`);
  const front = await shot(page, 'partial-front');
  const views = await page.evaluate(() => window.symcorrView.views);
  assert.ok(drawnFraction(front, middle(views[1].rect)) > 0.03, 'the scan is drawn');
  // From behind, the template's unseen back is in view.
  await page.evaluate(() => window.symcorrView.setCamera(Math.PI, 0.1));
  const unseen = corr.no_counterpart.filter((_, i) => i % 5 === 0).slice(0, 200);
  const hit = await visibleVertex(page, 'template', unseen);
  assert.ok(hit, 'an unseen point is in view from behind');
  const back = await shot(page, 'partial-back');
  const left = middle(views[0].rect);
  const [greyFront, greyBack] = [greyFraction(front, left), greyFraction(back, left)];
  assert.ok(greyFront < 0.2 && greyBack > 0.6, `the template grey from behind (${greyBack}), not in front (${greyFront})`);
  await page.mouse.click(hit.x, hit.y);
  const sel = await page.evaluate(() => window.symcorrView.selected);
  assert.equal(sel.template, hit.v);
  assert.equal(sel.noCounterpart, true);
  assert.equal(sel.target, null, 'no match marked');
  assert.match(await page.textContent('#info'), /does not show this point/);
  assert.deepEqual(errors, []);
  assert.deepEqual(requests, []);
  await page.close();
});

// Every .glb the commands above wrote: the demo's four meshes (matches and segments of both
// bodies), the labelled mesh and the track's animated template (morph targets with a
// per-frame animation). Blender and three.js read what the validator passes.
test('every glTF file the commands wrote passes the Khronos validator', async () => {
  const files = [];
  const walk = (dir) => {
    for (const e of fs.readdirSync(dir, { withFileTypes: true })) {
      const p = path.join(dir, e.name);
      if (e.isDirectory()) walk(p);
      else if (/\.(glb|gltf)$/.test(e.name)) files.push(p);
    }
  };
  walk(out);
  const names = files.map((f) => path.relative(out, f)).sort();
  for (const want of ['labels.glb', path.join('track', 'template_track.glb'), path.join('demo', 'template_matches.glb')]) {
    assert.ok(names.includes(want), `${want} among ${names.join(', ')}`);
  }
  for (const f of files) {
    const report = await gltfValidator.validateBytes(new Uint8Array(fs.readFileSync(f)));
    const { numErrors, numWarnings, messages } = report.issues;
    console.log(`${path.relative(repo, f)}: ${numErrors} errors, ${numWarnings} warnings, ${messages.length} messages`);
    assert.equal(numErrors + numWarnings, 0, `${f}: ${JSON.stringify(messages)}`);
  }
});
