// Live mode (README.md, "Live"): the bridge's foxglove.SceneUpdate and foxglove.FrameTransform
// channels (JSON-encoded) drawn as the mission view draws a run: map cubes, tree and path lines,
// vehicle and trajectories. Frames other than "world" follow the latest FrameTransform.
import * as THREE from 'three';
import { FoxgloveClient } from './foxglove_client.js';

const TOPICS = new Set(['/foxglove/map', '/foxglove/planner', '/foxglove/vehicle', '/tf']);
const decoder = new TextDecoder();

function colour(c, fallback = '#ffffff') {
  return c ? new THREE.Color(c.r, c.g, c.b) : new THREE.Color(fallback);
}
function applyPose(object, pose) {
  if (!pose) return;
  const p = pose.position || {}; const q = pose.orientation || {};
  object.position.set(p.x || 0, p.y || 0, p.z || 0);
  object.quaternion.set(q.x || 0, q.y || 0, q.z || 0, q.w ?? 1);
}

/** Cubes (spheres) of one entity as one InstancedMesh: a map has thousands. */
function instanced(geometry, primitives, sizeOf) {
  const mesh = new THREE.InstancedMesh(geometry, new THREE.MeshLambertMaterial({
    color: 0xffffff, transparent: primitives.some((p) => (p.color?.a ?? 1) < 1) }),
  primitives.length);
  const m = new THREE.Matrix4(); const o = new THREE.Object3D();
  primitives.forEach((prim, i) => {
    applyPose(o, prim.pose);
    const s = sizeOf(prim);
    o.scale.set(s.x || 1e-3, s.y || 1e-3, s.z || 1e-3);
    o.updateMatrix();
    mesh.setMatrixAt(i, m.copy(o.matrix));
    mesh.setColorAt(i, colour(prim.color));
  });
  mesh.computeBoundingSphere();
  return mesh;
}

function lineObject(line) {
  const pts = line.points || [];
  const index = [];
  const n = line.indices?.length ? line.indices.length : pts.length;
  const at = (k) => (line.indices?.length ? line.indices[k] : k);
  if (line.type === 2) {  // LINE_LIST
    for (let k = 0; k + 1 < n; k += 2) index.push(at(k), at(k + 1));
  } else {                // LINE_STRIP, LINE_LOOP
    for (let k = 1; k < n; k++) index.push(at(k - 1), at(k));
    if (line.type === 1 && n > 2) index.push(at(n - 1), at(0));
  }
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.Float32BufferAttribute(pts.flatMap((p) => [p.x, p.y, p.z]), 3));
  const perPoint = line.colors?.length === pts.length;
  if (perPoint) {
    g.setAttribute('color', new THREE.Float32BufferAttribute(
      line.colors.flatMap((c) => [c.r, c.g, c.b]), 3));
  }
  g.setIndex(index);
  const object = new THREE.LineSegments(g, new THREE.LineBasicMaterial(
    perPoint ? { vertexColors: true } : { color: colour(line.color) }));
  applyPose(object, line.pose);
  object.userData.segments = index.length / 2;
  return object;
}

export class LiveView {
  constructor(root, url, onChange) {
    this.root = root;
    this.onChange = onChange;
    this.frames = new Map();    // frame id -> Group following its FrameTransform
    this.entities = new Map();  // entity id -> Object3D
    this.state = { url, connected: false, messages: 0, status: '', entities: {},
      vehicle: null, vehicleUpdates: 0, connections: 0 };
    this.connect();
  }

  /** Connects, and again every 2 s while the bridge is not there: the page may be opened
   * before the mission starts, and a bridge restarted mid-mission is picked up. */
  connect() {
    this.client = new FoxgloveClient(this.state.url, {
      wants: (channel) => TOPICS.has(channel.topic) && channel.encoding === 'json',
      onOpen: () => {
        this.state.connected = true;
        this.state.connections++;
        this.state.status = '';
        this.onChange();
      },
      onStatus: (text) => { this.state.status = text; this.onChange(); },
      onClose: (reason) => {
        this.state.connected = false;
        this.state.status = `${reason}; retrying`;
        this.onChange();
        setTimeout(() => this.connect(), 2000);
      },
      onMessage: (channel, payload) => this.message(channel, payload),
    });
  }

  frame(id) {
    if (!id || id === 'world') return this.root;
    if (!this.frames.has(id)) {
      const g = new THREE.Group();
      g.name = `frame:${id}`;
      this.root.add(g);
      this.frames.set(id, g);
    }
    return this.frames.get(id);
  }

  message(channel, payload) {
    let m;
    try {
      m = JSON.parse(decoder.decode(payload));
    } catch (e) {
      this.state.status = `${channel.topic}: undecodable JSON (${e.message})`;
      return;
    }
    this.state.messages++;
    if (channel.schemaName === 'foxglove.FrameTransform') this.transform(m);
    else if (channel.schemaName === 'foxglove.FrameTransforms') (m.transforms || []).forEach((t) => this.transform(t));
    else if (channel.schemaName === 'foxglove.SceneUpdate') this.sceneUpdate(m);
    this.onChange();
  }

  transform(t) {
    if ((t.parent_frame_id || 'world') !== 'world') return;  // one level: world -> child
    const g = this.frame(t.child_frame_id);
    const p = t.translation || {}; const q = t.rotation || {};
    g.position.set(p.x || 0, p.y || 0, p.z || 0);
    g.quaternion.set(q.x || 0, q.y || 0, q.z || 0, q.w ?? 1);
    if (t.child_frame_id === 'vehicle') this.vehicleAt(g.position);
  }

  vehicleAt(p) {
    this.state.vehicle = { x: p.x, y: p.y, z: p.z };
    this.state.vehicleUpdates++;
  }

  remove(id) {
    const old = this.entities.get(id);
    if (!old) return;
    old.parent?.remove(old);
    old.traverse((o) => { o.geometry?.dispose(); });
    this.entities.delete(id);
    delete this.state.entities[id];
  }

  sceneUpdate(update) {
    for (const d of update.deletions || []) {
      if (d.type === 1) [...this.entities.keys()].forEach((id) => this.remove(id));
      else this.remove(d.id);
    }
    for (const e of update.entities || []) this.entity(e);
  }

  entity(e) {
    this.remove(e.id);
    const group = new THREE.Group();
    group.name = e.id;
    const counts = { cubes: 0, spheres: 0, lines: 0, segments: 0, triangles: 0 };
    if (e.cubes?.length) {
      group.add(instanced(new THREE.BoxGeometry(1, 1, 1), e.cubes, (c) => c.size || {}));
      counts.cubes = e.cubes.length;
    }
    if (e.spheres?.length) {
      group.add(instanced(new THREE.SphereGeometry(0.5, 16, 12), e.spheres, (s) => s.size || {}));
      counts.spheres = e.spheres.length;
    }
    for (const c of e.cylinders || []) {
      const mesh = new THREE.Mesh(new THREE.CylinderGeometry(0.5, 0.5, 1, 16),
        new THREE.MeshLambertMaterial({ color: colour(c.color) }));
      applyPose(mesh, c.pose);
      mesh.rotateX(Math.PI / 2);  // Foxglove cylinders lie along z, three.js's along y
      mesh.scale.set(c.size?.x || 1, c.size?.z || 1, c.size?.y || 1);
      group.add(mesh);
    }
    for (const a of e.arrows || []) {
      const length = (a.shaft_length || 0.5) + (a.head_length || 0.2);
      const arrow = new THREE.ArrowHelper(new THREE.Vector3(1, 0, 0), new THREE.Vector3(), length,
        colour(a.color), a.head_length || 0.2, a.head_diameter || 0.15);
      const holder = new THREE.Group();
      applyPose(holder, a.pose);
      holder.add(arrow);
      group.add(holder);
    }
    for (const l of e.lines || []) {
      const object = lineObject(l);
      counts.lines++;
      counts.segments += object.userData.segments;
      group.add(object);
    }
    for (const t of e.triangles || []) {
      const g = new THREE.BufferGeometry();
      g.setAttribute('position', new THREE.Float32BufferAttribute((t.points || []).flatMap((p) => [p.x, p.y, p.z]), 3));
      if (t.indices?.length) g.setIndex(t.indices);
      g.computeVertexNormals();
      const mesh = new THREE.Mesh(g, new THREE.MeshLambertMaterial({ color: colour(t.color), side: THREE.DoubleSide }));
      applyPose(mesh, t.pose);
      counts.triangles += (t.indices?.length || t.points?.length || 0) / 3;
      group.add(mesh);
    }
    this.frame(e.frame_id).add(group);
    this.entities.set(e.id, group);
    this.state.entities[e.id] = counts;
    // Without a transform for the vehicle, its entity's own pose is where it is.
    if (e.id === 'vehicle' && (!e.frame_id || e.frame_id === 'world')) {
      const pose = e.cubes?.[0]?.pose || e.arrows?.[0]?.pose || e.spheres?.[0]?.pose || e.cylinders?.[0]?.pose;
      if (pose?.position) this.vehicleAt(pose.position);
    }
  }
}
