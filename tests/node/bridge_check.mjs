// Connects to a live teleop_bridge with the Foxglove WebSocket protocol's own client
// (@foxglove/ws-protocol), subscribes to every advertised channel and decodes every message
// with the channel's omgidl schema (@foxglove/omgidl-parser + @foxglove/omgidl-serialization):
// what Foxglove and Lichtblick will see.
//
//   node [--experimental-websocket] tests/node/bridge_check.mjs ws://127.0.0.1:PORT SECONDS
//
// Checks, each a failure with a message naming the topic:
//  - serverInfo offers no clientPublish; every teleop/* channel is `cdr` with an `omgidl` schema
//    that parses and gives a reader for its schemaName; every bridge/* channel is `json` with a
//    `jsonschema` schema that parses;
//  - bridge/scene (foxglove.SceneUpdate) arrives, its entities hold only finite numbers, and its
//    triangles are as many as teleop/mesh_topology's (decoded from CDR) for the bodies shown;
//    bridge/transforms names the tip frame;
//  - every message decodes; the state topics' `seq` and receive times advance; every decoded
//    force is finite;
//  - the scene (latched) arrives, as do states and mesh frames.
// Exit status 0 when all hold, 1 otherwise.
import { createRequire } from "node:module";
import { checkFiniteForces } from "./decoded_checks.mjs";
import { failureList, requireWebSocket } from "./check_lib.mjs";

const require = createRequire(import.meta.url);
const { FoxgloveClient } = require("@foxglove/ws-protocol");
const { parseIDL } = require("@foxglove/omgidl-parser");
const { MessageReader } = require("@foxglove/omgidl-serialization");

const [url, secondsText] = process.argv.slice(2);
if (!url || !secondsText) {
  console.error("usage: node bridge_check.mjs ws://127.0.0.1:PORT SECONDS");
  process.exit(2);
}
requireWebSocket();
const { failures, fail } = failureList(50);

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
    if (ch.topic.startsWith("bridge/")) {
      if (ch.encoding !== "json") fail(`${ch.topic}: encoding ${ch.encoding}`);
      if (ch.schemaEncoding !== "jsonschema") fail(`${ch.topic}: schemaEncoding ${ch.schemaEncoding}`);
      try {
        const schema = JSON.parse(ch.schema);
        if (schema.title !== ch.schemaName) fail(`${ch.topic}: schema title ${schema.title}`);
      } catch (e) {
        fail(`${ch.topic}: the JSON schema does not parse: ${e.message}`);
      }
      const state = { topic: ch.topic, json: true, count: 0, last: undefined };
      channels.set(ch.id, state);
      bySub.set(client.subscribe(ch.id), state);
      continue;
    }
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
  if (c.json) {
    try {
      c.last = JSON.parse(new TextDecoder().decode(data));
      c.count++;
    } catch (e) {
      if (decodeFailures++ < 5) fail(`${c.topic}: a message is not JSON: ${e.message}`);
    }
    return;
  }
  if (c.topic === "teleop/mesh_topology") c.keep = true;
  try {
    decoded = c.reader.readMessage(new Uint8Array(data.buffer, data.byteOffset, data.byteLength));
  } catch (e) {
    if (decodeFailures++ < 5) fail(`${c.topic}: a message does not decode: ${e.message}`);
    return;
  }
  c.count++;
  if (c.keep) (c.decoded ??= new Map()).set(decoded.object_id, decoded);
  checkFiniteForces(decoded, c.topic, fail);
  if (ordered.has(c.topic)) {
    const seq = BigInt(decoded.seq);
    if (seq <= c.seq || timestamp < c.time) c.backwards++;
    c.seq = seq;
    c.time = timestamp;
  }
});

// The newest foxglove.SceneUpdate against the topology decoded from CDR.
function checkScene(list) {
  const scene = list.find((c) => c.topic === "bridge/scene");
  const topology = list.find((c) => c.topic === "teleop/mesh_topology");
  const transforms = list.find((c) => c.topic === "bridge/transforms");
  if (!scene?.last) return fail("bridge/scene: no foxglove.SceneUpdate arrived");
  const entities = scene.last.entities ?? [];
  const ids = entities.map((e) => e.id);
  for (const id of ["environment", "deformable", "robot"]) {
    if (!ids.includes(id)) fail(`bridge/scene: no entity '${id}' (${ids.join(", ")})`);
  }
  const numbers = [];
  const walk = (v) => {
    if (typeof v === "number") numbers.push(v);
    else if (v && typeof v === "object") Object.values(v).forEach(walk);
  };
  walk(entities);
  if (!numbers.every(Number.isFinite)) fail("bridge/scene: a number is not finite");
  const tris = entities.flatMap((e) => e.triangles ?? []);
  const drawn = tris.reduce((n, t) => n + t.indices.length / 3, 0);
  const expected = [...(topology?.decoded?.values() ?? [])].reduce((n, t) => n + t.triangle_indices.length / 3, 0);
  if (tris.length === 0 || drawn !== expected) {
    fail(`bridge/scene: ${drawn} triangles in ${tris.length} lists, teleop/mesh_topology has ${expected}`);
  }
  for (const t of tris) {
    if (t.indices.some((i) => !Number.isInteger(i) || i < 0 || i >= t.points.length)) fail("bridge/scene: an index out of range");
  }
  const robot = entities.find((e) => e.id === "robot");
  if (!(robot?.spheres?.length >= 1)) fail("bridge/scene: no tip sphere");
  const names = (transforms?.last?.transforms ?? []).map((t) => t.child_frame_id);
  if (!names.includes("tip")) fail(`bridge/transforms: no 'tip' frame (${names.join(", ")})`);
  console.log(`  bridge/scene: ${entities.length} entities, ${drawn} triangles (topology ${expected}), ${numbers.length} numbers finite`);
}

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
for (const topic of ["teleop/slave_state_view", "teleop/master_state_view", "teleop/mesh_frame",
  "bridge/scene", "bridge/transforms", "bridge/plot"]) {
  if (count(topic) < 20) fail(`${topic}: ${count(topic)} messages (at least 20 expected)`);
}
checkScene([...channels.values()]);
if (failures.length > 0) {
  console.error(`${failures.length} failures`);
  process.exit(1);
}
console.log(`OK: ${channels.size} channels, every message decoded with its omgidl or JSON schema`);
process.exit(0);
