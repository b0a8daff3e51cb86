// Reads an MCAP recording made by teleop_record with the MCAP project's own TypeScript reader
// (@mcap/core) and decodes every message with the IDL schema stored in the file
// (@foxglove/omgidl-parser + @foxglove/omgidl-serialization): the file is what other tools
// (Foxglove, Lichtblick) will see.
//
//   node tests/node/mcap_check.mjs FILE.mcap
//
// Checks, each a failure with a message naming the record or topic:
//  - the indexed reader opens it (magic, footer, summary CRC) and the data section's CRC matches
//    the Data End record;
//  - every message reads with CRC validation (each chunk's CRC), and the streaming reader, which
//    walks every record including this project's extension record, reads the same number;
//  - every schema is `omgidl` and parses, every channel is `cdr`, every message decodes with
//    its channel's schema;
//  - the core topics (master_command, slave_state, master_state) hold messages whose `seq` and
//    MCAP sequence numbers advance, and every decoded force is finite;
//  - per-channel counts equal the Statistics record.
// Exit status 0 when all hold, 1 otherwise.
import { readFileSync } from "node:fs";
import { createRequire } from "node:module";

import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import { loadDecompressHandlers } from "@mcap/support";
import { checkFiniteForces } from "./decoded_checks.mjs";

const require = createRequire(import.meta.url);
const { parseIDL } = require("@foxglove/omgidl-parser");
const { MessageReader } = require("@foxglove/omgidl-serialization");
const { crc32 } = require("@foxglove/crc");

const file = process.argv[2];
if (!file) {
  console.error("usage: node mcap_check.mjs FILE.mcap");
  process.exit(2);
}
const failures = [];
const fail = (what) => {
  failures.push(what);
  console.error(`FAIL ${what}`);
};

const bytes = readFileSync(file);
const decompressHandlers = await loadDecompressHandlers();
const readable = {
  size: async () => BigInt(bytes.length),
  read: async (offset, length) => bytes.subarray(Number(offset), Number(offset + length)),
};

// 1. the indexed reader: footer, summary (its CRC is checked when it is read)
const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers });
console.log(
  `${file}: ${bytes.length} bytes, ${reader.chunkIndexes.length} chunks, ` +
    `${reader.channelsById.size} channels, ${reader.schemasById.size} schemas, ` +
    `${reader.statistics?.messageCount ?? "?"} messages`,
);
if (reader.dataSectionCrc === undefined) {
  fail("the Data End record holds no data section CRC");
} else {
  const crc = crc32(bytes.subarray(0, Number(reader.dataEndOffset)));
  if (crc !== reader.dataSectionCrc) {
    fail(`data section CRC ${crc} != ${reader.dataSectionCrc} recorded in Data End`);
  }
}

// 2. the schemas: omgidl, each parses and gives a reader for its type
const decoders = new Map();
for (const [id, schema] of reader.schemasById) {
  if (schema.encoding !== "omgidl") fail(`schema ${id} (${schema.name}): encoding ${schema.encoding}`);
  try {
    const definitions = parseIDL(new TextDecoder().decode(schema.data));
    decoders.set(id, new MessageReader(schema.name, definitions));
  } catch (e) {
    fail(`schema ${id} (${schema.name}) does not parse: ${e.message}`);
  }
}
for (const [id, channel] of reader.channelsById) {
  if (channel.messageEncoding !== "cdr") fail(`channel ${id} (${channel.topic}): encoding ${channel.messageEncoding}`);
  if (!decoders.has(channel.schemaId)) fail(`channel ${id} (${channel.topic}): no usable schema`);
}

// 3. every message, with the chunks' CRCs checked, decoded with its schema
const checked = new Set(["teleop/master_command", "teleop/slave_state", "teleop/master_state"]);
const perChannel = new Map();
let total = 0;
let decodeFailures = 0;
for await (const message of reader.readMessages({ validateCrcs: true })) {
  const channel = reader.channelsById.get(message.channelId);
  const decoder = decoders.get(channel.schemaId);
  let decoded;
  try {
    decoded = decoder.readMessage(message.data);
  } catch (e) {
    if (decodeFailures++ < 5) fail(`${channel.topic}: message at ${message.logTime} does not decode: ${e.message}`);
    continue;
  }
  total++;
  let c = perChannel.get(message.channelId);
  if (!c) {
    c = { topic: channel.topic, count: 0, seq: -1n, sequence: -1, backwards: 0 };
    perChannel.set(message.channelId, c);
  }
  c.count++;
  checkFiniteForces(decoded, channel.topic, fail);
  if (checked.has(channel.topic)) {
    const seq = BigInt(decoded.seq);
    if (seq <= c.seq || message.sequence <= c.sequence) c.backwards++;
    c.seq = seq;
    c.sequence = message.sequence;
  }
}
for (const c of perChannel.values()) {
  console.log(`  ${c.topic.padEnd(30)} ${String(c.count).padStart(8)} messages decoded`);
  if (checked.has(c.topic) && c.backwards > 0) {
    fail(`${c.topic}: seq or sequence did not advance ${c.backwards} times`);
  }
}
for (const topic of checked) {
  const c = [...perChannel.values()].find((x) => x.topic === topic);
  if (!c || c.count < 100) fail(`${topic}: ${c ? c.count : 0} messages (at least 100 expected)`);
}
const stats = reader.statistics;
if (!stats) {
  fail("no Statistics record");
} else {
  if (BigInt(total) !== stats.messageCount) fail(`${total} messages read, Statistics says ${stats.messageCount}`);
  for (const [id, n] of stats.channelMessageCounts) {
    const got = perChannel.get(id)?.count ?? 0;
    if (BigInt(got) !== n) fail(`channel ${id}: ${got} messages read, Statistics says ${n}`);
  }
}

// 4. the streaming reader: every record from the first byte to the last, CRCs checked
const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true });
stream.append(bytes);
let streamed = 0;
let unknown = 0;
for (let record; (record = stream.nextRecord()); ) {
  if (record.type === "Message") streamed++;
  if (record.type === "Unknown") unknown++;
}
if (!stream.done()) fail("the streaming reader did not reach the end of the file");
if (streamed !== total) fail(`the streaming reader read ${streamed} messages, the indexed one ${total}`);
console.log(
  `  read ${total} messages (indexed, CRCs checked) and ${streamed} (streamed; ` +
    `${unknown} extension records skipped): ${failures.length === 0 ? "ok" : `${failures.length} failures`}`,
);
process.exit(failures.length === 0 ? 0 : 1);
