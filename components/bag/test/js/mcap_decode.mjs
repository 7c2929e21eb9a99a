// Reads an MCAP file the way a Foxglove user's tools do — @mcap/core's indexed reader (footer,
// summary, chunk indexes, CRCs) — and decodes every message with Foxglove's OMG IDL modules
// from the schema stored in the file (interfaces/test/js/cdr_json.mjs), for
// components/bag/test/record_play_test.cc to compare with what was published.
//
//   node mcap_decode.mjs FILE
//
// Output, one JSON document: {"channels": {topic: {"schema": name, "metadata": {...},
// "messages": [decoded JSON text, ...]}}}; exit 1 with {"error": ...} when the file or a
// message does not read. AUV_BAG_JS_DIR overrides where the modules are (default <repo>/js).
import { createRequire } from "node:module";
import { readFileSync } from "node:fs";
import path from "node:path";
import { fileURLToPath } from "node:url";

import { cdrDecoder } from "../../../../interfaces/test/js/cdr_json.mjs";

const here = path.dirname(fileURLToPath(import.meta.url));
const jsDir = process.env.AUV_BAG_JS_DIR ?? path.resolve(here, "../../../../js");
const require = createRequire(path.join(jsDir, "package.json"));
const { McapIndexedReader } = require("@mcap/core");
const fzstd = require("fzstd");
const lz4 = require("lz4js");

const decompressHandlers = {
  zstd: (data, size) => fzstd.decompress(data, new Uint8Array(Number(size))),
  lz4: (data, size) => Uint8Array.from(lz4.decompress(data, Number(size))),
};

try {
  const bytes = new Uint8Array(readFileSync(process.argv[2]));
  const readable = {
    size: async () => BigInt(bytes.length),
    read: async (offset, size) => bytes.subarray(Number(offset), Number(offset + size)),
  };
  const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers });
  const channels = {};
  const decoders = new Map();
  for (const channel of reader.channelsById.values()) {
    const schema = reader.schemasById.get(channel.schemaId);
    if (schema.encoding !== "omgidl" || channel.messageEncoding !== "cdr")
      throw new Error(`${channel.topic}: ${schema.encoding}/${channel.messageEncoding}`);
    decoders.set(channel.id, cdrDecoder(jsDir, schema.name, new TextDecoder().decode(schema.data)));
    channels[channel.topic] = {
      schema: schema.name,
      metadata: Object.fromEntries(channel.metadata),
      messages: [],
    };
  }
  for await (const m of reader.readMessages({ validateCrcs: true })) {
    const channel = reader.channelsById.get(m.channelId);
    channels[channel.topic].messages.push(decoders.get(m.channelId)(m.data));
  }
  process.stdout.write(JSON.stringify({ channels }) + "\n");
} catch (error) {
  process.stdout.write(JSON.stringify({ error: String(error?.stack ?? error) }) + "\n");
  process.exitCode = 1;
}
