// Three.js objects for the layers the server converted (README.md, "What each view shows").
// Every layer is one binary buffer and a JSON description of the typed arrays in it.
import * as THREE from 'three';

const TYPES = { f32: Float32Array, u32: Uint32Array, u8: Uint8Array };

/** The typed arrays of a layer, viewed in place in its buffer. */
export function arraysOf(layer, buffer) {
  const out = {};
  for (const [name, a] of Object.entries(layer.arrays)) {
    out[name] = new TYPES[a.type](buffer, a.offset, a.count * a.itemSize);
  }
  return out;
}

export async function fetchLayer(layer) {
  const response = await fetch(layer.url);
  if (!response.ok) throw new Error(`${layer.url}: HTTP ${response.status}`);
  return arraysOf(layer, await response.arrayBuffer());
}

/** Set by the page before loading: software GL (no GPU) samples textures on the CPU; the page
 * renders on demand, so it is told when a texture arrives (or fails) after its level. */
export const renderHints = {
  softwareGl: false, texturesPending: 0, texturesArrived: 0, onTexture: () => {},
  onError: () => {},
};

const textureLoader = new THREE.TextureLoader();
const textures = new Map();
function texture(url) {
  if (!textures.has(url)) {
    renderHints.texturesPending++;
    const t = textureLoader.load(url, () => {
      renderHints.texturesPending--;
      renderHints.texturesArrived++;
      renderHints.onTexture();
    }, undefined, () => {
      renderHints.texturesPending--;
      renderHints.onError(new Error(`texture ${url} could not be loaded`));
    });
    t.colorSpace = THREE.SRGBColorSpace;
    t.anisotropy = 1;
    // Bilinear in the nearest mipmap instead of trilinear: +25 % frames per second on
    // SwiftShader (bench/README.md), at the price of faint seams between mipmap levels.
    if (renderHints.softwareGl) t.minFilter = THREE.LinearMipmapNearestFilter;
    textures.set(url, t);
  }
  return textures.get(url);
}

// A reconstruction's faces point to the cameras that saw them: back faces are culled unless
// asked for (software GL draws twice the triangles otherwise, README.md "Levels of detail").
let modelSide = THREE.FrontSide;
export function setModelBackFaces(level, show) {
  modelSide = show ? THREE.DoubleSide : THREE.FrontSide;
  for (const m of level?.userData.materials ?? []) { m.side = modelSide; m.needsUpdate = true; }
}

/** sRGB bytes per vertex as the linear floats three.js blends (as it decodes an sRGB texture). */
function linearColours(bytes) {
  const out = new Float32Array(bytes.length);
  const c = new THREE.Color();
  for (let i = 0; i < bytes.length; i += 3) {
    c.setRGB(bytes[i] / 255, bytes[i + 1] / 255, bytes[i + 2] / 255, THREE.SRGBColorSpace);
    out[i] = c.r; out[i + 1] = c.g; out[i + 2] = c.b;
  }
  return new THREE.BufferAttribute(out, 3);
}

/** A textured model level: one vertex and index buffer shared by its tiles, one object per
 * tile (so three.js skips the tiles out of view), one unlit material per atlas page; a coarse
 * level the atlas could not follow carries its colours per vertex instead (README.md). */
export function meshObject(layer, a) {
  const position = new THREE.BufferAttribute(a.position, 3);
  const uv = a.uv && new THREE.BufferAttribute(a.uv, 2);
  const color = a.color && linearColours(a.color);
  const index = new THREE.BufferAttribute(a.index, 1);
  const materials = []; const materialOf = new Map();
  const materialFor = (url) => {
    if (!materialOf.has(url)) {
      materialOf.set(url, materials.length);
      // The texture carries the light of the photos: drawn unlit. Without one, shaded.
      materials.push(url
        ? new THREE.MeshBasicMaterial({ map: texture(url), side: modelSide })
        : color ? new THREE.MeshBasicMaterial({ vertexColors: true, side: modelSide })
          : new THREE.MeshLambertMaterial({ color: 0xb0a890, side: modelSide }));
    }
    return materialOf.get(url);
  };
  const tiles = layer.tiles?.length ? layer.tiles : [{ groups: layer.groups }];
  for (const tile of tiles) tile.groups.forEach((g) => materialFor(g.texture));
  const level = new THREE.Group();
  for (const tile of tiles) {
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', position);
    if (uv) g.setAttribute('uv', uv);
    if (color) g.setAttribute('color', color);
    g.setIndex(index);
    for (const group of tile.groups) g.addGroup(group.start, group.count, materialFor(group.texture));
    if (!color && tile.groups.some((group) => !group.texture)) g.computeVertexNormals();
    if (tile.center) {
      // The tile's own bounds (the shared buffer spans the whole level): what culling tests.
      g.boundingSphere = new THREE.Sphere(new THREE.Vector3(...tile.center), tile.radius);
    } else {
      g.computeBoundingSphere();
    }
    level.add(new THREE.Mesh(g, materials));
  }
  level.userData.materials = materials;
  return level;
}

export function pointsObject(layer, a) {
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(a.position, 3));
  let material;
  if (a.color) {
    g.setAttribute('color', new THREE.BufferAttribute(a.color, 3, true));
    material = new THREE.PointsMaterial({ vertexColors: true, size: layer.pointSize || 2,
      sizeAttenuation: false });
  } else {
    material = new THREE.PointsMaterial({ color: layer.color || '#ffffff',
      size: layer.pointSize || 7, sizeAttenuation: false });
  }
  return new THREE.Points(g, material);
}

/** Depth colour ramp (z down: deeper = darker blue, shallower = sand). */
function depthColour(t, out) {
  return out.setHSL(0.08 + 0.5 * t, 0.55, 0.65 - 0.3 * t);
}

export function voxelsObject(layer, a) {
  const n = layer.count;
  const mesh = new THREE.InstancedMesh(new THREE.BoxGeometry(1, 1, 1),
    new THREE.MeshLambertMaterial({ color: 0xffffff }), n);
  let zmin = Infinity; let zmax = -Infinity;
  for (let i = 0; i < n; i++) {
    zmin = Math.min(zmin, a.center[3 * i + 2]);
    zmax = Math.max(zmax, a.center[3 * i + 2]);
  }
  const m = new THREE.Matrix4(); const p = new THREE.Vector3(); const s = new THREE.Vector3();
  const q = new THREE.Quaternion(); const c = new THREE.Color();
  for (let i = 0; i < n; i++) {
    p.set(a.center[3 * i], a.center[3 * i + 1], a.center[3 * i + 2]);
    s.setScalar(a.size[i] * 0.98);  // a hair apart, so voxel edges show
    mesh.setMatrixAt(i, m.compose(p, q, s));
    mesh.setColorAt(i, depthColour(zmax > zmin ? (p.z - zmin) / (zmax - zmin) : 0.5, c));
  }
  mesh.computeBoundingSphere();
  return mesh;
}

export function segmentsObject(layer, a) {
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(a.position, 3));
  return new THREE.LineSegments(g, new THREE.LineBasicMaterial({ color: layer.color || '#888',
    transparent: true, opacity: 0.6 }));
}

/** Many polylines in one draw call: index pairs within each line. */
export function polylinesObject(layer, a) {
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(a.position, 3));
  const index = [];
  for (let l = 0; l < a.start.length; l++) {
    for (let k = 1; k < a.vertices[l]; k++) index.push(a.start[l] + k - 1, a.start[l] + k);
  }
  g.setIndex(index);
  return new THREE.LineSegments(g, new THREE.LineBasicMaterial({ color: layer.color || '#fff' }));
}

const CAMERA_COLOURS = ['#ff4040', '#40ff40', '#4080ff', '#ffff40', '#ff40ff', '#40ffff'];

/** SfM cameras as small pyramids (apex at the centre, base along the optical axis z). */
export function camerasObject(layer, a, size = 0.3) {
  const positions = []; const colours = []; const c = new THREE.Color();
  const corners = [[-0.5, -0.375], [0.5, -0.375], [0.5, 0.375], [-0.5, 0.375]];
  for (let i = 0; i < layer.count; i++) {
    const o = a.center.subarray(3 * i, 3 * i + 3); const ax = a.axes.subarray(9 * i, 9 * i + 9);
    const base = corners.map(([u, v]) => [0, 1, 2].map((k) =>
      o[k] + size * (ax[6 + k] + u * ax[k] + v * ax[3 + k])));
    for (let k = 0; k < 4; k++) {
      positions.push(...o, ...base[k], ...base[k], ...base[(k + 1) % 4]);
    }
    c.set(CAMERA_COLOURS[a.camera[i] % CAMERA_COLOURS.length]);
    for (let k = 0; k < 16; k++) colours.push(c.r, c.g, c.b);
  }
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.Float32BufferAttribute(positions, 3));
  g.setAttribute('color', new THREE.Float32BufferAttribute(colours, 3));
  return new THREE.LineSegments(g, new THREE.LineBasicMaterial({ vertexColors: true }));
}

export function spheresObject(layer, a, radius = 0.4) {
  const mesh = new THREE.InstancedMesh(new THREE.SphereGeometry(radius, 16, 12),
    new THREE.MeshLambertMaterial({ color: layer.color || '#e74c3c' }), layer.count);
  const m = new THREE.Matrix4();
  for (let i = 0; i < layer.count; i++) {
    mesh.setMatrixAt(i, m.makeTranslation(a.position[3 * i], a.position[3 * i + 1],
      a.position[3 * i + 2]));
  }
  mesh.computeBoundingSphere();
  return mesh;
}

export const BUILDERS = {
  mesh: meshObject, points: pointsObject, voxels: voxelsObject, segments: segmentsObject,
  polylines: polylinesObject, cameras: camerasObject, spheres: spheresObject,
};

/** How many things a layer draws, as the page reports them (window.__auvView.counts). */
export function drawnCount(layer, a) {
  switch (layer.type) {
    case 'mesh': return a.index.length / 3;
    case 'points': return a.position.length / 3;
    case 'voxels': return a.size.length;
    case 'segments': return a.position.length / 6;
    case 'polylines': return a.start.length;
    case 'cameras': return a.center.length / 3;
    case 'spheres': return a.position.length / 3;
    default: return 0;
  }
}
