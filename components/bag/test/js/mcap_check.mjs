// Reads an MCAP file with @mcap/core (Foxglove's TypeScript library, js/README.md) twice —
// McapIndexedReader (footer, summary, chunk indexes, chunk CRCs) and McapStreamReader (every
// record in file order, chunk CRCs) — and prints what each saw as JSON, for
// components/bag/test/js_interop_test.cc to compare with what our writer wrote.
//
//   node mcap_check.mjs FILE [--topic T --start NS --end NS]
//
// Modules come from the repository's js/node_modules (AUV_BAG_JS_DIR overrides).
import { createRequire } from "node:module";
import { readFileSync } from "node:fs";
import path from "node:path";
import { fileURLToPath } from "node:url";

const here = path.dirname(fileURLToPath(import.meta.url));
const jsDir = process.env.AUV_BAG_JS_DIR ?? path.resolve(here, "../../../../js");
const require = createRequire(path.join(jsDir, "package.json"));
const { McapIndexedReader, McapStreamReader } = require("@mcap/core");
const { crc32 } = require("@foxglove/crc");
const fzstd = require("fzstd");
const lz4 = require("lz4js");

const decompressHandlers = {
  zstd: (data, size) => fzstd.decompress(data, new Uint8Array(Number(size))),
  lz4: (data, size) => Uint8Array.from(lz4.decompress(data, Number(size))),
};

const args = process.argv.slice(2);
const file = args[0];
const option = (name) => {
  const at = args.indexOf(name);
  return at >= 0 ? args[at + 1] : undefined;
};
const bytes = new Uint8Array(readFileSync(file));

const hex = (data) => Buffer.from(data.buffer, data.byteOffset, data.byteLength).toString("hex");
const schemaJson = (s) => ({
  id: s.id,
  name: s.name,
  encoding: s.encoding,
  data: Buffer.from(s.data).toString("utf8"),
});
const channelJson = (c) => ({
  id: c.id,
  schemaId: c.schemaId,
  topic: c.topic,
  messageEncoding: c.messageEncoding,
  metadata: Object.fromEntries(c.metadata),
});
const messageJson = (m) => ({
  channelId: m.channelId,
  sequence: m.sequence,
  logTime: m.logTime.toString(),
  publishTime: m.publishTime.toString(),
  data: hex(m.data),
});

async function indexed() {
  const readable = {
    size: async () => BigInt(bytes.length),
    read: async (offset, size) => bytes.subarray(Number(offset), Number(offset + size)),
  };
  const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers });
  const out = {
    header: reader.header,
    schemas: [...reader.schemasById.values()].map(schemaJson),
    channels: [...reader.channelsById.values()].map(channelJson),
    chunkCount: reader.chunkIndexes.length,
    summaryOffsetOpcodes: [...reader.summaryOffsetsByOpcode.keys()].sort((a, b) => a - b),
    statistics: {
      messageCount: reader.statistics.messageCount.toString(),
      chunkCount: reader.statistics.chunkCount,
      messageStartTime: reader.statistics.messageStartTime.toString(),
      messageEndTime: reader.statistics.messageEndTime.toString(),
      channelMessageCounts: Object.fromEntries(
        [...reader.statistics.channelMessageCounts].map(([id, n]) => [id, n.toString()]),
      ),
    },
    // @mcap/core does not check the Data End CRC itself: it is checked here.
    dataSectionCrc: {
      stored: reader.dataSectionCrc ?? 0,
      computed: crc32(bytes.subarray(0, Number(reader.dataEndOffset))),
    },
    metadata: [],
    messages: [],
  };
  for await (const m of reader.readMetadata()) {
    out.metadata.push({ name: m.name, metadata: Object.fromEntries(m.metadata) });
  }
  for await (const m of reader.readMessages({ validateCrcs: true })) {
    out.messages.push(messageJson(m));
  }
  const topic = option("--topic");
  if (topic !== undefined) {
    out.filtered = [];
    const filter = {
      topics: [topic],
      startTime: BigInt(option("--start")),
      endTime: BigInt(option("--end")),
      validateCrcs: true,
    };
    for await (const m of reader.readMessages(filter)) out.filtered.push(messageJson(m));
  }
  return out;
}

function stream() {
  const reader = new McapStreamReader({ decompressHandlers, validateCrcs: true });
  reader.append(bytes);
  const schemas = new Map();
  const channels = new Map();
  const out = { recordCounts: {}, messages: [] };
  for (let record; (record = reader.nextRecord()); ) {
    out.recordCounts[record.type] = (out.recordCounts[record.type] ?? 0) + 1;
    if (record.type === "Schema") schemas.set(record.id, schemaJson(record));
    if (record.type === "Channel") channels.set(record.id, channelJson(record));
    if (record.type === "Message") out.messages.push(messageJson(record));
  }
  out.done = reader.done();
  out.schemas = [...schemas.values()];
  out.channels = [...channels.values()];
  return out;
}

try {
  const result = { indexed: await indexed(), stream: stream() };
  process.stdout.write(JSON.stringify(result) + "\n");
} catch (error) {
  process.stdout.write(JSON.stringify({ error: String(error?.stack ?? error) }) + "\n");
  process.exitCode = 1;
}
