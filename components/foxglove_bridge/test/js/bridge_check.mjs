// Connects to the foxglove_bridge with Foxglove's own client (@foxglove/ws-protocol's
// FoxgloveClient over `ws`, js/README.md), subscribes to every advertised channel whose topic
// starts with PREFIX, and decodes one sample of each with @foxglove/omgidl-serialization and
// the schema the bridge advertised (cdr_json.mjs). Then it sends malformed messages and
// expects an error status for each, pauses a second client's socket while SLOW_TOPIC
// streams (a client that does not read), and checks the bridge still answers.
//
//   node bridge_check.mjs URL PREFIX COUNT SLOW_TOPIC TIMEOUT_MS
//
// Output lines: `channel <topic> <json>` per advertised channel, `sample <topic> <json>` per
// decoded sample, `status <level> <message>`, `slow <fast client frames> <slow client frames>`,
// `alive`, `done`. Exit 1 with a message on stderr on a timeout or an error.
// Modules come from the repository's js/node_modules (AUV_JS_DIR overrides).
import { createRequire } from "node:module";
import path from "node:path";
import { fileURLToPath } from "node:url";

import { cdrDecoder } from "../../../../interfaces/test/js/cdr_json.mjs";

const here = path.dirname(fileURLToPath(import.meta.url));
const jsDir = process.env.AUV_JS_DIR ?? path.resolve(here, "../../../../js");
const require = createRequire(path.join(jsDir, "package.json"));
const { FoxgloveClient } = require("@foxglove/ws-protocol");
const WebSocket = require("ws");

const [url, prefix, countText, slowTopic, timeoutText] = process.argv.slice(2);
const count = Number(countText);
const fail = (why) => {
  process.stderr.write(`bridge_check: ${why}\n`);
  process.exit(1);
};
setTimeout(() => fail("timed out"), Number(timeoutText)).unref();
const print = (line) => process.stdout.write(line + "\n");

const connect = () => {
  const ws = new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
  return { ws, client: new FoxgloveClient({ ws }) };
};

const main = connect();
const channels = new Map();  // id -> channel
const subscriptions = new Map();  // subscription id -> channel
const decoded = new Set();
let slowChannel;
let statuses = 0;
let fastFrames = 0;
let phase = "samples";

main.client.on("error", (e) => fail(`client error: ${e}`));
main.client.on("advertise", (list) => {
  for (const c of list) {
    channels.set(c.id, c);
    if (c.topic === slowTopic) slowChannel = c;
    if (!c.topic.startsWith(prefix)) continue;
    print(`channel ${c.topic} ${JSON.stringify({ encoding: c.encoding, schemaName: c.schemaName, schemaEncoding: c.schemaEncoding })}`);
    subscriptions.set(main.client.subscribe(c.id), c);
  }
});
main.client.on("status", (s) => {
  print(`status ${s.level} ${s.message.replace(/\n/g, " ")}`);
  if (phase === "malformed" && ++statuses === malformed.length) startSlow();
});
main.client.on("message", ({ subscriptionId, data }) => {
  const c = subscriptions.get(subscriptionId);
  if (!c) return;
  if (c.topic === slowTopic) {
    fastFrames++;
    return;
  }
  if (decoded.has(c.topic)) return;
  decoded.add(c.topic);
  try {
    const bytes = new Uint8Array(data.buffer, data.byteOffset, data.byteLength);
    print(`sample ${c.topic} ${cdrDecoder(jsDir, c.schemaName, c.schema)(bytes)}`);
  } catch (error) {
    fail(`${c.topic}: ${error.message ?? error}`);
  }
  if (decoded.size === count) startMalformed();
});

const malformed = ["{", "[]", '{"op":"subscribe","subscriptions":[{"id":-1,"channelId":1}]}',
  '{"op":"unsubscribe","subscriptionIds":[123456]}', '{"op":"explode"}', new Uint8Array([0x42, 1]),
  new Uint8Array([2, 1, 0])];
function startMalformed() {
  phase = "malformed";
  for (const m of malformed) main.ws.send(m);  // raw frames past the client's API
}

function startSlow() {
  phase = "slow";
  if (!slowChannel) fail(`${slowTopic} was not advertised`);
  subscriptions.set(main.client.subscribe(slowChannel.id), slowChannel);
  const slow = connect();
  let slowFrames = 0;
  slow.client.on("advertise", () => {});
  slow.client.on("message", () => slowFrames++);
  slow.client.on("open", () => {
    slow.client.subscribe(slowChannel.id);
    // A client that stops reading: the kernel's buffers fill, then the bridge's.
    setTimeout(() => slow.ws._socket.pause(), 200);
  });
  setTimeout(() => {
    print(`slow ${fastFrames} ${slowFrames}`);
    slow.ws.terminate();
    const alive = connect();
    alive.client.on("serverInfo", () => {
      print("alive");
      print("done");
      process.exit(0);
    });
  }, 3000);
}
