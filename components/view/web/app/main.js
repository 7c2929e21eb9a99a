// auv view: loads the scene the server prepared (/api/scene) and draws it with three.js.
// window.__auvView reports what is drawn, for the tests and the benchmark (README.md, "Tests").
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { BUILDERS, drawnCount, fetchLayer, renderHints, setModelBackFaces } from './layers.js';
import { LiveView } from './live.js';

const started = performance.now();
const state = window.__auvView = {
  ready: false, kind: null, counts: {}, frames: 0, texturesDrawn: 0, errors: [], firstFrameMs: null,
  modelLevel: null, live: null, vehicle: null,
};
window.addEventListener('error', (e) => state.errors.push(String(e.message)));
window.addEventListener('unhandledrejection', (e) => state.errors.push(String(e.reason)));

const container = document.getElementById('view');
const renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: true });
renderer.setPixelRatio(1);  // software GL: every pixel counts
renderer.setSize(container.clientWidth, container.clientHeight);
container.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color('#0b1e2d');
scene.add(new THREE.AmbientLight(0xffffff, 1.2));
const sun = new THREE.DirectionalLight(0xffffff, 1.5);
sun.position.set(0.3, 1, 0.5);
scene.add(sun);
const camera = new THREE.PerspectiveCamera(50, container.clientWidth / container.clientHeight,
  0.05, 5000);
camera.position.set(10, 10, 10);
const controls = new OrbitControls(camera, renderer.domElement);

// The data is NED (x north, y east, z down); three.js is y up: x -> -z, y -> x, z -> -y.
const root = new THREE.Group();
root.matrixAutoUpdate = false;
root.matrix.set(0, 1, 0, 0, 0, 0, -1, 0, -1, 0, 0, 0, 0, 0, 0, 1);
scene.add(root);

let dirty = true;
const requestRender = () => { dirty = true; };
controls.addEventListener('change', requestRender);
// Software GL while the camera moves: half the resolution (a quarter of the pixels to texture:
// 4.5-6.2 -> 8.0-9.5 fps zoomed in on a textured model, bench/README.md), full when it stops.
function setMoving(moving) {
  if (!state.softwareGl) return;
  renderer.setPixelRatio(moving ? 0.5 : 1);
  renderer.setSize(container.clientWidth, container.clientHeight);
  requestRender();
}
controls.addEventListener('start', () => setMoving(true));
controls.addEventListener('end', () => setMoving(false));
window.addEventListener('resize', () => {
  camera.aspect = container.clientWidth / container.clientHeight;
  camera.updateProjectionMatrix();
  renderer.setSize(container.clientWidth, container.clientHeight);
  requestRender();
});

let spin = null;  // the benchmark's orbit: {until, frames, start}
function frame(now) {
  requestAnimationFrame(frame);
  if (spin) {
    const angle = 0.01;
    const offset = camera.position.clone().sub(controls.target);
    offset.applyAxisAngle(new THREE.Vector3(0, 1, 0), angle);
    camera.position.copy(controls.target).add(offset);
    camera.lookAt(controls.target);
    dirty = true;
  }
  if (!dirty) return;
  dirty = false;
  renderer.render(scene, camera);
  state.frames++;
  // Which arrivals this frame includes: counted, not timed (a frame's timestamp is its start,
  // earlier than a texture that arrived within it).
  state.texturesDrawn = renderHints.texturesArrived;
  if (spin) {
    spin.frames++;
    if (now >= spin.until) { spin.resolve(spin.frames / ((now - spin.start) / 1000)); spin = null; }
  }
  if (state.firstFrameMs === null && (root.children.length || state.ready)) {
    state.firstFrameMs = now - started;
  }
}
requestAnimationFrame(frame);

/** Frames per second while the camera orbits for `seconds` (the benchmark). */
state.benchmark = (seconds, { moving = false } = {}) => new Promise((resolve) => {
  if (moving) setMoving(true);  // as while the user drags (software GL: half resolution)
  spin = { start: performance.now(), until: performance.now() + seconds * 1000, frames: 0,
    resolve: (fps) => { if (moving) setMoving(false); resolve(fps); } };
});
state.fit = fitView;
state.three = { scene, root, renderer, camera };
/** Moves the camera `factor` times closer to what it looks at, as a wheel zoom does, and
 * resolves with the model level then on screen (the tests). */
state.zoom = async (factor) => {
  camera.position.sub(controls.target).divideScalar(factor).add(controls.target);
  controls.update();
  if (model.auto && model.levels.length) await showLevel(autoLevel());
  return model.level;
};
/** Shows level k (a number) or 'auto' and resolves once it is on screen (the benchmark). */
state.setLevel = async (k) => {
  model.auto = k === 'auto';
  await showLevel(model.auto ? autoLevel() : k);
  await new Promise((resolve) => requestAnimationFrame(() => requestAnimationFrame(resolve)));
  return model.level;
};
/** Hides (or shows again) everything: the benchmark's anchor, an empty scene in the same page. */
state.showAll = (visible) => { root.visible = visible; requestRender(); };

function fitView() {
  const box = new THREE.Box3().setFromObject(root);
  if (box.isEmpty()) return false;
  const centre = box.getCenter(new THREE.Vector3());
  const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 1);
  controls.target.copy(centre);
  const distance = radius / Math.sin((camera.fov * Math.PI) / 360);
  camera.position.copy(centre).add(new THREE.Vector3(0.6, 0.7, 0.9).normalize().multiplyScalar(distance));
  camera.near = distance / 1000;
  camera.far = distance * 10;
  camera.updateProjectionMatrix();
  controls.update();
  requestRender();
  return true;
}

const objects = new Map();  // layer id -> Object3D
function addLayerControl(layer, object) {
  const label = document.createElement('label');
  const box = document.createElement('input');
  box.type = 'checkbox';
  box.checked = object.visible;
  box.dataset.layer = layer.id;
  box.onchange = () => { object.visible = box.checked; requestRender(); };
  const swatch = document.createElement('span');
  swatch.className = 'swatch';
  swatch.style.background = layer.color || '#aaa';
  label.append(box, swatch, `${layer.label} (${layer.count})`);
  document.getElementById('layers').append(label);
}

async function loadLayer(layer) {
  const arrays = await fetchLayer(layer);
  const object = BUILDERS[layer.type](layer, arrays);
  object.name = layer.id;
  object.visible = layer.visible !== false;
  objects.set(layer.id, object);
  state.counts[layer.id] = drawnCount(layer, arrays);
  return object;
}

// Levels of detail (README.md): a triangle smaller than a few pixels shows nothing more, and
// software GL (SwiftShader, llvmpipe: no GPU) pays for every triangle and texel on the CPU.
// "auto" keeps about PIXELS_PER_TRIANGLE pixels of the model's projected bounding sphere per
// triangle (zoomed out: coarse; zoomed in: finer), twice as many per triangle on software GL
// as a GPU needs four times fewer, at most the server's default level (--max-triangles); a
// level is fetched when first chosen.
const debugInfo = renderer.getContext().getExtension('WEBGL_debug_renderer_info');
state.renderer = debugInfo ? renderer.getContext().getParameter(debugInfo.UNMASKED_RENDERER_WEBGL) : '';
state.softwareGl = /swiftshader|llvmpipe|softpipe|software/i.test(state.renderer);
const PIXELS_PER_TRIANGLE = state.softwareGl ? 64 : 16;
renderHints.softwareGl = state.softwareGl;
renderHints.onTexture = requestRender;
renderHints.onError = (e) => report(e);
Object.defineProperty(state, 'texturesPending', { get: () => renderHints.texturesPending });
Object.defineProperty(state, 'texturesArrived', { get: () => renderHints.texturesArrived });
const model = { levels: [], shown: null, level: null, auto: true, loading: new Map(), sphere: null };

function autoLevel() {
  if (!model.sphere) return model.defaultLevel;
  const distance = Math.max(camera.position.distanceTo(model.sphere.center), 1e-6);
  const half = Math.tan((camera.fov * Math.PI) / 360) * distance;
  const radiusPx = (model.sphere.radius / half) * (renderer.domElement.height / 2);
  const pixels = Math.PI * radiusPx * radiusPx;
  // A level coloured per vertex (README.md) has no texels between its vertices: four times the
  // triangles for the same detail.
  const budget = (level) => Math.min(
    pixels / (level.vertexColours ? PIXELS_PER_TRIANGLE / 4 : PIXELS_PER_TRIANGLE), model.maxTriangles);
  // Levels run finest (0) to coarsest: the finest one within the budget, else the coarsest.
  const k = model.levels.findIndex((level) => level.triangles <= budget(level));
  return k < 0 ? model.levels.length - 1 : k;
}

async function showLevel(k) {
  if (model.level === k) return;
  const layer = model.levels[k].layerInfo;
  if (!objects.has(layer.id)) {
    if (!model.loading.has(k)) model.loading.set(k, loadLayer(layer));
    await model.loading.get(k);
  }
  const object = objects.get(layer.id);
  if (model.shown) { object.visible = model.shown.visible; root.remove(model.shown); }
  root.add(object);
  model.shown = object;
  model.level = k;
  state.modelLevel = k;
  state.counts.model = state.counts[layer.id];
  const select = document.getElementById('lod-select');
  if (select && !model.auto) select.value = k;
  const label = document.getElementById('lod-shown');
  if (label) label.textContent = ` showing level ${k}`;
  requestRender();
}

function updateAutoLevel() {
  if (model.auto && model.levels.length) showLevel(autoLevel()).catch(report);
}

/** The coarsest level first (a first frame at once), then the level "auto" picks. */
async function loadModel(manifest) {
  const info = manifest.model;
  model.levels = info.levels.map((level) => ({ ...level,
    layerInfo: manifest.layers.find((l) => l.id === level.layer) }));
  model.defaultLevel = info.default;
  state.modelLevels = info.levels;
  model.maxTriangles = info.levels[info.default].triangles;
  await showLevel(info.coarsest);
  model.sphere = new THREE.Box3().setFromObject(model.shown).getBoundingSphere(new THREE.Sphere());
  fitView();
  state.fitted = true;
  const select = document.createElement('select');
  select.id = 'lod-select';
  select.append(new Option('auto', 'auto'));
  model.levels.forEach((level, k) => select.append(
    new Option(`level ${k}: ${level.triangles.toLocaleString()} triangles`, String(k))));
  select.onchange = () => {
    model.auto = select.value === 'auto';
    if (model.auto) updateAutoLevel();
    else showLevel(Number(select.value)).catch(report);
  };
  const back = document.createElement('input');
  back.type = 'checkbox';
  back.id = 'back-faces';
  back.onchange = () => {
    for (const k of model.levels.keys()) setModelBackFaces(objects.get(model.levels[k].layer), back.checked);
    requestRender();
  };
  const backLabel = document.createElement('label');
  backLabel.append(back, 'back faces');
  const shown = document.createElement('span');
  shown.id = 'lod-shown';
  document.getElementById('lod').append('model detail ', select, shown, backLabel);
  await showLevel(autoLevel());
  state.defaultLevelMs = performance.now() - started;  // the level "auto" picks, on screen
  state.autoLevel = model.level;
  controls.addEventListener('end', updateAutoLevel);  // not mid-drag: a fetch would stutter
  addLayerControl({ id: 'model', label: 'textured model', count: info.triangles },
    { get visible() { return model.shown?.visible ?? true; },
      set visible(v) { if (model.shown) model.shown.visible = v; } });
}

function report(error) {
  state.errors.push(String(error?.message || error));
  console.error(error);
}

async function main() {
  const response = await fetch('/api/scene');
  const manifest = await response.json();
  state.kind = manifest.kind;
  document.getElementById('title').textContent = `auv view: ${manifest.name} (${manifest.kind})`;
  document.title = `auv view: ${manifest.name}`;
  const notes = document.getElementById('notes');
  for (const note of manifest.notes || []) {
    const div = document.createElement('div');
    div.textContent = note;
    notes.append(div);
  }
  const pending = [];
  if (manifest.model) pending.push(loadModel(manifest));
  for (const layer of manifest.layers) {
    if (layer.type === 'mesh') continue;  // the model's levels: loadModel
    pending.push(loadLayer(layer).then((object) => {
      root.add(object);
      addLayerControl(layer, object);
      requestRender();
    }));
  }
  const results = await Promise.allSettled(pending);
  results.filter((r) => r.status === 'rejected').forEach((r) => report(r.reason));
  if (!state.fitted) state.fitted = fitView();
  if (manifest.live) startLive(manifest.live);
  state.ready = true;
  requestRender();
}

function startLive(url) {
  const status = document.getElementById('status');
  const live = new LiveView(root, url, () => {
    state.live = live.state;
    state.vehicle = live.state.vehicle;
    status.textContent = `live ${url}: ${live.state.connected ? 'connected' : 'not connected'}` +
      `, ${live.state.messages} messages ${live.state.status}`;
    // Frame the view once there is something to frame: the map, else the vehicle.
    if (!state.fitted && (live.state.entities.map || live.state.vehicle)) {
      state.fitted = fitView();
    }
    requestRender();
  });
  state.live = live.state;
}

main().catch(report);
