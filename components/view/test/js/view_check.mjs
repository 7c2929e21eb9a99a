// Loads an `auv view` page in headless Chromium (Debian's) with puppeteer-core and prints one
// JSON line: what window.__auvView reports, the share of canvas pixels that are not the
// background, console errors, and in live mode the vehicle's positions some time apart.
//   node view_check.mjs <url> <chromium> [--live-seconds S] [--benchmark S [--all-levels]]
//                       [--zoom FACTOR] [--size WxH]
import { createRequire } from 'node:module';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

// Modules come from the repository's js/node_modules (AUV_VIEW_JS_DIR overrides).
const here = path.dirname(fileURLToPath(import.meta.url));
const jsDir = process.env.AUV_VIEW_JS_DIR ?? path.resolve(here, '../../../../js');
const require = createRequire(path.join(jsDir, 'package.json'));
const puppeteer = require('puppeteer-core');

const [url, chromium, ...rest] = process.argv.slice(2);
// Tests talk to loopback only: without these Chromium resolves and calls Google's services
// and looks for cast devices on the LAN (eth0 sent ~50 packets per page load here, counted by
// no-external-traffic). No host name resolves but 127.0.0.1.
const LOOPBACK_ONLY = ['--disable-background-networking', '--disable-component-update',
  '--disable-sync', '--no-first-run', '--disable-default-apps', '--disable-domain-reliability',
  '--disable-client-side-phishing-detection', '--metrics-recording-only',
  '--disable-features=MediaRouter,DialMediaRouteProvider,OptimizationHints,Translate',
  '--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE 127.0.0.1'];
const option = (name, fallback) => {
  const i = rest.indexOf(name);
  return i >= 0 ? rest[i + 1] : fallback;
};
const liveSeconds = Number(option('--live-seconds', 0));
const benchmarkSeconds = Number(option('--benchmark', 0));
const [width, height] = option('--size', '1024x768').split('x').map(Number);

const browser = await puppeteer.launch({
  executablePath: chromium,
  headless: true,
  // Software GL: no GPU in CI or here (SwiftShader through ANGLE).
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
    '--ignore-gpu-blocklist', `--window-size=${width},${height}`, ...LOOPBACK_ONLY],
});
const result = { errors: [], requestsFailed: [] };
try {
  const page = await browser.newPage();
  await page.setViewport({ width, height });
  const delayTextures = Number(option('--delay-textures-ms', 0));
  if (delayTextures > 0) {
    // Atlas pages that arrive after everything else (a large page over a slow link).
    await page.setRequestInterception(true);
    page.on('request', (r) => {
      if (/\.(png|jpe?g)$/i.test(r.url())) setTimeout(() => r.continue(), delayTextures);
      else r.continue();
    });
  }
  page.on('console', (m) => { if (m.type() === 'error') result.errors.push(m.text()); });
  page.on('pageerror', (e) => result.errors.push(String(e.message || e)));
  page.on('requestfailed', (r) => result.requestsFailed.push(r.url()));
  page.on('response', (r) => { if (r.status() >= 400) result.errors.push(`${r.url()}: HTTP ${r.status()}`); });
  const t0 = Date.now();
  await page.goto(url, { waitUntil: 'load' });
  await page.waitForFunction(
    () => window.__auvView?.ready && window.__auvView.firstFrameMs !== null, { timeout: 120000 });
  result.readyMs = Date.now() - t0;
  // Texture pages decode after their level is on screen (the page renders on demand).
  await page.waitForFunction(() => window.__auvView.texturesPending === 0, { timeout: 120000 });
  result.texturesMs = Date.now() - t0;
  // ... and the page draws them by itself, untouched (a user sees no black model).
  result.drawnAfterTextures = await page.waitForFunction(
    () => window.__auvView.texturesDrawn === window.__auvView.texturesArrived, { timeout: 5000 })
    .then(() => true, () => false);
  if (liveSeconds > 0) {
    await page.waitForFunction(() => window.__auvView.vehicle !== null, { timeout: 30000 });
    result.vehicleFirst = await page.evaluate(() => ({ ...window.__auvView.vehicle,
      updates: window.__auvView.live.vehicleUpdates }));
    await new Promise((r) => setTimeout(r, liveSeconds * 1000));
    result.vehicleLast = await page.evaluate(() => ({ ...window.__auvView.vehicle,
      updates: window.__auvView.live.vehicleUpdates }));
  }
  if (benchmarkSeconds > 0) {
    // Warm-up (shader compilation, texture upload, mipmaps), then three rounds of the model
    // and the anchor — the same page, renderer and canvas with nothing drawn but the background
    // — interleaved, so a change of machine load hits both; medians reported.
    const bench = () => page.evaluate((s) => window.__auvView.benchmark(s), benchmarkSeconds);
    const show = (v) => page.evaluate((v) => window.__auvView.showAll(v), v);
    await page.evaluate(() => window.__auvView.benchmark(1));
    result.fpsRounds = [];
    result.fpsEmptyRounds = [];
    for (let round = 0; round < 3; round++) {
      result.fpsRounds.push(await bench());
      await show(false);
      result.fpsEmptyRounds.push(await bench());
      await show(true);
    }
    const median = (a) => [...a].sort((x, y) => x - y)[Math.floor(a.length / 2)];
    result.fps = median(result.fpsRounds);
    result.fpsEmpty = median(result.fpsEmptyRounds);
    result.defaultLevel = await page.evaluate(() => window.__auvView.modelLevel);
    if (rest.includes('--all-levels')) {
      // Every level from the same view (the fitted one), coarsest first.
      result.levels = [];
      const levels = await page.evaluate(() => window.__auvView.modelLevels);
      for (let k = levels.length - 1; k >= 0; k--) {
        await page.evaluate((k) => window.__auvView.setLevel(k), k);
        const fps = await page.evaluate((s) => window.__auvView.benchmark(s), benchmarkSeconds);
        result.levels.push({ level: k, triangles: levels[k].triangles, fps });
      }
      await page.evaluate(() => window.__auvView.setLevel('auto'));
    }
  }
  const zoom = Number(option('--zoom', 0));
  if (zoom > 0) {
    result.levelBeforeZoom = await page.evaluate(() => window.__auvView.modelLevel);
    result.trianglesBeforeZoom = await page.evaluate(() => window.__auvView.counts.model);
    result.levelAfterZoom = await page.evaluate((z) => window.__auvView.zoom(z), zoom);
    result.trianglesAfterZoom = await page.evaluate(() => window.__auvView.counts.model);
    if (benchmarkSeconds > 0) {
      // Zoomed in on a finer level: only its tiles in view are drawn.
      result.fpsZoomed = await page.evaluate((s) => window.__auvView.benchmark(s), benchmarkSeconds);
      result.fpsZoomedMoving = await page.evaluate(
        (s) => window.__auvView.benchmark(s, { moving: true }), benchmarkSeconds);
    }
    result.levelAfterZoomOut = await page.evaluate((z) => window.__auvView.zoom(1 / z), zoom);
  }
  // Wait for two more frames so the canvas holds what was loaded last.
  const frames = await page.evaluate(() => window.__auvView.frames);
  await page.evaluate(() => window.__auvView.fit());
  await page.waitForFunction((f) => window.__auvView.frames > f, { timeout: 30000 }, frames);
  result.view = await page.evaluate(() => {
    const v = window.__auvView;
    return { kind: v.kind, counts: v.counts, frames: v.frames, firstFrameMs: v.firstFrameMs,
      modelLevel: v.modelLevel, defaultLevelMs: v.defaultLevelMs, errors: v.errors, live: v.live };
  });
  // Pixels that differ from the background (#0b1e2d), read back from the WebGL canvas.
  result.nonBackground = await page.evaluate(() => {
    const canvas = document.querySelector('#view canvas');
    const copy = document.createElement('canvas');
    copy.width = canvas.width;
    copy.height = canvas.height;
    const ctx = copy.getContext('2d');
    ctx.drawImage(canvas, 0, 0);
    const data = ctx.getImageData(0, 0, copy.width, copy.height).data;
    let differ = 0, lit = 0;
    for (let i = 0; i < data.length; i += 4) {
      if (Math.abs(data[i] - 11) + Math.abs(data[i + 1] - 30) + Math.abs(data[i + 2] - 45) > 24) differ++;
      if (data[i] + data[i + 1] + data[i + 2] > 150) lit++;  // brighter than the background
    }
    return { differ: differ / (data.length / 4), lit: lit / (data.length / 4) };
  });
  result.lit = result.nonBackground.lit;
  result.nonBackground = result.nonBackground.differ;
} catch (e) {
  result.errors.push(`view_check: ${e.message}`);
} finally {
  await browser.close();
}
console.log(JSON.stringify(result));
