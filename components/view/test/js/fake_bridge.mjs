// A stand-in for components/foxglove_bridge in the live test: @foxglove/ws-protocol's own
// FoxgloveServer (npm) publishing what the bridge publishes, JSON-encoded with Foxglove's
// schemas — the map as cubes, the planner's tree and path as lines, the vehicle and its
// trajectories, and /tf world -> vehicle — with the vehicle going round a circle.
// Listens on the port given (default: a free one), prints {"port": N} once listening; runs
// until killed.
import { createRequire } from 'node:module';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

// Modules come from the repository's js/node_modules (AUV_VIEW_JS_DIR overrides).
const here = path.dirname(fileURLToPath(import.meta.url));
const jsDir = process.env.AUV_VIEW_JS_DIR ?? path.resolve(here, '../../../../js');
const require = createRequire(path.join(jsDir, 'package.json'));
const { FoxgloveServer } = require('@foxglove/ws-protocol');
const { WebSocketServer } = require('ws');

const server = new FoxgloveServer({ name: 'fake-foxglove-bridge' });
const ws = new WebSocketServer({ host: '127.0.0.1', port: Number(process.argv[2] || 0),
  handleProtocols: (protocols) => server.handleProtocols(protocols) });
ws.on('listening', () => console.log(JSON.stringify({ port: ws.address().port })));
ws.on('connection', (conn, req) => server.handleConnection(conn, `${req.socket.remotePort}`));
server.on('error', (e) => console.error(`fake bridge: ${e}`));

const channel = (topic, schemaName) => server.addChannel({ topic, encoding: 'json', schemaName,
  schema: JSON.stringify({ type: 'object' }), schemaEncoding: 'jsonschema' });
const map = channel('/foxglove/map', 'foxglove.SceneUpdate');
const planner = channel('/foxglove/planner', 'foxglove.SceneUpdate');
const vehicle = channel('/foxglove/vehicle', 'foxglove.SceneUpdate');
const tf = channel('/tf', 'foxglove.FrameTransform');
// A channel the viewer must ignore (CDR, as the bridge forwards DDS topics).
server.addChannel({ topic: 'nav/odometry', encoding: 'cdr', schemaName: 'auv_msgs::msg::Odometry',
  schema: 'struct Odometry { double x; };', schemaEncoding: 'omgidl' });

const identity = { x: 0, y: 0, z: 0, w: 1 };
const pose = (x, y, z) => ({ position: { x, y, z }, orientation: identity });
const time = () => ({ sec: Math.floor(Date.now() / 1000), nsec: (Date.now() % 1000) * 1e6 });
const entity = (id, frame, fields) => ({ timestamp: time(), frame_id: frame, id,
  lifetime: { sec: 0, nsec: 0 }, frame_locked: frame !== 'world', metadata: [], arrows: [],
  cubes: [], spheres: [], cylinders: [], lines: [], triangles: [], texts: [], models: [], ...fields });
const send = (chan, message) => server.sendMessage(chan, BigInt(Date.now()) * 1000000n,
  new TextEncoder().encode(JSON.stringify(message)));

const cubes = [];
for (let i = 0; i < 12; i++) {
  for (let k = 0; k < 5; k++) {
    cubes.push({ pose: pose(8, -3 + 0.5 * i, 1 + 0.5 * k), size: { x: 0.5, y: 0.5, z: 0.5 },
      color: { r: 0.6, g: 0.5, b: 0.4, a: 1 } });
  }
}
const line = (type, points, colour) => ({ type, pose: pose(0, 0, 0), thickness: 0.05,
  scale_invariant: false, points, color: colour, colors: [], indices: [] });
const point = (x, y, z) => ({ x, y, z });

const truePath = []; const estimated = [];
let t = 0;
setInterval(() => {
  t += 0.1;
  const x = 4 * Math.cos(t * 0.5); const y = 4 * Math.sin(t * 0.5); const z = 2;
  truePath.push(point(x, y, z));
  estimated.push(point(x + 0.05 * t, y, z));
  send(tf, { timestamp: time(), parent_frame_id: 'world', child_frame_id: 'vehicle',
    translation: { x, y, z }, rotation: identity });
  send(vehicle, { deletions: [], entities: [
    entity('vehicle', 'vehicle', { cubes: [{ pose: pose(0, 0, 0), size: { x: 1.6, y: 0.5, z: 0.5 },
      color: { r: 1, g: 0.8, b: 0, a: 1 } }] }),
    entity('trajectory_true', 'world', { lines: [line(0, truePath, { r: 1, g: 1, b: 1, a: 1 })] }),
    entity('trajectory_estimated', 'world', { lines: [line(0, estimated, { r: 0.2, g: 0.8, b: 0.4, a: 1 })] }),
  ] });
  if (Math.round(t * 10) % 10 === 1) {
    send(map, { deletions: [], entities: [entity('map', 'world', { cubes })] });
    send(planner, { deletions: [], entities: [
      entity('tree', 'world', { lines: [line(2, [point(0, 0, 2), point(1, 1, 2), point(0, 0, 2), point(1, -1, 2)], { r: 0.5, g: 0.5, b: 0.5, a: 1 })] }),
      entity('path', 'world', { lines: [line(0, [point(0, 0, 2), point(3, 1, 2), point(6, 0, 2)], { r: 1, g: 0.6, b: 0, a: 1 })] }),
    ] });
  }
}, 100);
