// Connects to a live teleop_bridge with the Foxglove WebSocket protocol's own client
// (@foxglove/ws-protocol), subscribes to every advertised channel and decodes every message
// with the channel's omgidl schema (@foxglove/omgidl-parser + @foxglove/omgidl-serialization):
// what Foxglove and Lichtblick will see.
//
//   node [--experimental-websocket] tests/node/bridge_check.mjs ws://127.0.0.1:PORT SECONDS
//
// Checks, each a failure with a message naming the topic:
//  - serverInfo offers no clientPublish; every channel is `cdr` with an `omgidl` schema that
//    parses and gives a reader for its schemaName;
//  - every message decodes; the state topics' `seq` and receive times advance; every decoded
//    force is finite;
//  - the scene (latched) arrives, as do states and mesh frames.
// Exit status 0 when all hold, 1 otherwise.
import { createRequire } from "node:module";
import { checkFiniteForces } from "./decoded_checks.mjs";

const require = createRequire(import.meta.url);
const { FoxgloveClient } = require("@foxglove/ws-protocol");
const { parseIDL } = require("@foxglove/omgidl-parser");
const { MessageReader } = require("@foxglove/omgidl-serialization");

const [url, secondsText] = process.argv.slice(2);
if (!url || !secondsText) {
  console.error("usage: node bridge_check.mjs ws://127.0.0.1:PORT SECONDS");
  process.exit(2);
}
if (typeof WebSocket !== "function") {
  console.error("FAIL this Node.js has no WebSocket: run it with --experimental-websocket (Node >= 20.10)");
  process.exit(1);
}
const failures = [];
const fail = (what) => {
  if (failures.length < 50) console.error(`FAIL ${what}`);
  failures.push(what);
};

const client = new FoxgloveClient({ ws: new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]) });
const channels = new Map(); // channel id -> {topic, reader}
const bySub = new Map(); // subscription id -> channel state
const ordered = new Set(["teleop/slave_state_view", "teleop/master_state_view", "teleop/slave_state_monitor",
  "teleop/master_state_monitor", "teleop/slave_state", "teleop/master_state", "teleop/master_command"]);
let serverInfo;


client.on("error", (e) => fail(`websocket error: ${e?.message ?? e}`));
client.on("serverInfo", (info) => {
  serverInfo = info;
  if ((info.capabilities ?? []).includes("clientPublish")) fail("serverInfo offers clientPublish");
});
client.on("status", (s) => console.log(`status (level ${s.level}): ${s.message}`));
client.on("advertise", (list) => {
  for (const ch of list) {
    if (ch.encoding !== "cdr") fail(`${ch.topic}: encoding ${ch.encoding}`);
    if (ch.schemaEncoding !== "omgidl") fail(`${ch.topic}: schemaEncoding ${ch.schemaEncoding}`);
    let reader;
    try {
      reader = new MessageReader(ch.schemaName, parseIDL(ch.schema));
    } catch (e) {
      fail(`${ch.topic}: schema ${ch.schemaName} does not parse: ${e.message}`);
      continue;
    }
    const state = { topic: ch.topic, reader, count: 0, seq: -1n, time: -1n, backwards: 0 };
    channels.set(ch.id, state);
    bySub.set(client.subscribe(ch.id), state);
  }
});
let decodeFailures = 0;
client.on("message", ({ subscriptionId, timestamp, data }) => {
  const c = bySub.get(subscriptionId);
  if (!c) return fail(`a message for unknown subscription ${subscriptionId}`);
  let decoded;
  try {
    decoded = c.reader.readMessage(new Uint8Array(data.buffer, data.byteOffset, data.byteLength));
  } catch (e) {
    if (decodeFailures++ < 5) fail(`${c.topic}: a message does not decode: ${e.message}`);
    return;
  }
  c.count++;
  checkFiniteForces(decoded, c.topic, fail);
  if (ordered.has(c.topic)) {
    const seq = BigInt(decoded.seq);
    if (seq <= c.seq || timestamp < c.time) c.backwards++;
    c.seq = seq;
    c.time = timestamp;
  }
});

await new Promise((resolve) => setTimeout(resolve, Number(secondsText) * 1000));
client.close();
if (!serverInfo) fail("no serverInfo");
if (channels.size === 0) fail("no channel advertised");
for (const c of channels.values()) {
  console.log(`  ${c.topic.padEnd(30)} ${String(c.count).padStart(8)} messages decoded`);
  if (c.backwards > 0) fail(`${c.topic}: seq or receive time did not advance ${c.backwards} times`);
}
const count = (topic) => [...channels.values()].find((c) => c.topic === topic)?.count ?? 0;
if (count("teleop/scene") < 1) fail("teleop/scene: the latched scene did not arrive");
for (const topic of ["teleop/slave_state_view", "teleop/master_state_view", "teleop/mesh_frame"]) {
  if (count(topic) < 20) fail(`${topic}: ${count(topic)} messages (at least 20 expected)`);
}
if (failures.length > 0) {
  console.error(`${failures.length} failures`);
  process.exit(1);
}
console.log(`OK: ${channels.size} channels, every message decoded with its omgidl schema`);
process.exit(0);
