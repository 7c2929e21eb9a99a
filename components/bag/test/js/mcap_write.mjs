// Writes an MCAP file with @mcap/core's McapWriter (Foxglove's TypeScript library,
// js/README.md) and prints the messages it wrote as JSON, for
// components/bag/test/js_interop_test.cc to check that our reader reads files others write.
//
//   node mcap_write.mjs FILE MODE     MODE: chunked-lz4 | chunked | unchunked
//
// Modules come from the repository's js/node_modules (AUV_BAG_JS_DIR overrides).
import { createRequire } from "node:module";
import { writeFileSync } from "node:fs";
import path from "node:path";
import { fileURLToPath } from "node:url";

const here = path.dirname(fileURLToPath(import.meta.url));
const jsDir = process.env.AUV_BAG_JS_DIR ?? path.resolve(here, "../../../../js");
const require = createRequire(path.join(jsDir, "package.json"));
const { McapWriter } = require("@mcap/core");
const lz4 = require("lz4js");

const [file, mode] = process.argv.slice(2);
const parts = [];
let size = 0n;
const writable = {
  position: () => size,
  write: async (buffer) => {
    parts.push(Buffer.from(buffer));
    size += BigInt(buffer.byteLength);
  },
};
const writer = new McapWriter({
  writable,
  useChunks: mode !== "unchunked",
  chunkSize: 4096,
  compressChunk:
    mode === "chunked-lz4"
      ? (data) => ({ compression: "lz4", compressedData: Uint8Array.from(lz4.compress(data)) })
      : undefined,
});
await writer.start({ profile: "", library: "mcap_write.mjs" });
const schemaId = await writer.registerSchema({
  name: "test_msgs::msg::Ping",
  encoding: "omgidl",
  data: new TextEncoder().encode("module test_msgs { module msg { struct Ping { long n; }; }; };"),
});
const topics = ["/ping", "/pong", "/late"];
const channels = [];
for (const topic of topics) {
  channels.push(
    await writer.registerChannel({
      schemaId,
      topic,
      messageEncoding: "cdr",
      metadata: new Map([["offered_qos_profiles", topic === "/late" ? "best_effort" : "reliable"]]),
    }),
  );
}
let seed = 12345;
const random = () => (seed = (seed * 1103515245 + 12345) % 2147483648) >> 8;
const written = [];
for (let i = 0; i < 300; i++) {
  const k = i % 3;
  // /late goes backwards in time: its messages land in chunks that overlap the others'.
  const logTime = k === 2 ? 1_000_000n - BigInt(i) * 3001n : 1000n + BigInt(i) * 3000n;
  const data = new Uint8Array(random() % 300).map(() => random() % 256);
  await writer.addMessage({
    channelId: channels[k],
    sequence: i,
    logTime,
    publishTime: logTime + 1n,
    data,
  });
  written.push({
    topic: topics[k],
    sequence: i,
    logTime: logTime.toString(),
    publishTime: (logTime + 1n).toString(),
    data: Buffer.from(data).toString("hex"),
  });
}
await writer.addMetadata({ name: "origin", metadata: new Map([["writer", "@mcap/core"]]) });
await writer.end();
writeFileSync(file, Buffer.concat(parts));
process.stdout.write(JSON.stringify({ messages: written }) + "\n");
