// Checks who teleop_bridge lets in when it runs with TLS and an access token (--tls-cert,
// --tls-key, --token-file): run by run_access_check.sh against a bridge on 127.0.0.1 whose
// self-signed certificate is trusted through NODE_EXTRA_CA_CERTS.
//
//   node [--experimental-websocket] tests/node/access_check.mjs https://127.0.0.1:PORT TOKEN
//
// Checks, each a failure with a message:
//  - the page: 401 without a token and with a wrong one; 200 with ?token= and with
//    "Authorization: Bearer", and it is the bridge's page;
//  - wss with the token: serverInfo (no clientPublish capability) and the advertised channels
//    arrive; a binary client message (what a client publish would be) is refused with a status
//    message saying the bridge is read-only;
//  - wss without the token, and plain ws to the TLS port: never opened.
// Exit status 0 when all hold, 1 otherwise.
import { failureList, requireWebSocket } from "./check_lib.mjs";
const [base, token] = process.argv.slice(2);
if (!base || !token) {
  console.error("usage: node access_check.mjs https://127.0.0.1:PORT TOKEN");
  process.exit(2);
}
requireWebSocket();
const { failures, fail } = failureList();
const wssBase = base.replace(/^https:/, "wss:");

async function page(suffix, headers, expected) {
  try {
    const r = await fetch(`${base}/${suffix}`, { headers });
    const text = await r.text();
    if (r.status !== expected) fail(`GET /${suffix} ${JSON.stringify(headers)}: status ${r.status}, expected ${expected}`);
    if (expected === 200 && !text.includes("teleop_bridge")) fail(`GET /${suffix}: not the bridge's page`);
    console.log(`  GET /${suffix || ""} ${Object.keys(headers).join(" ")}: ${r.status}`);
  } catch (e) {
    fail(`GET /${suffix}: ${e.cause?.message ?? e.message}`);
  }
}

// Opens a WebSocket; resolves with what happened within `ms`.
function session(url, ms, onOpen) {
  return new Promise((resolve) => {
    const got = { opened: false, ops: [], statuses: [], channels: [] };
    let ws;
    try {
      ws = new WebSocket(url, ["foxglove.websocket.v1"]);
    } catch (e) {
      resolve({ ...got, error: e.message });
      return;
    }
    const timer = setTimeout(() => { ws.close(); resolve(got); }, ms);
    ws.onopen = () => { got.opened = true; onOpen?.(ws); };
    ws.onmessage = (ev) => {
      if (typeof ev.data !== "string") return;
      const m = JSON.parse(ev.data);
      got.ops.push(m.op);
      if (m.op === "serverInfo") got.capabilities = m.capabilities;
      if (m.op === "advertise") got.channels.push(...m.channels.map((c) => c.topic));
      if (m.op === "status") got.statuses.push(m.message);
    };
    ws.onerror = () => { got.error = "refused"; };
    ws.onclose = () => { clearTimeout(timer); resolve(got); };
  });
}

await page("", {}, 401);
await page("?token=not-the-token-at-all-0000", {}, 401);
await page(`?token=${token}`, {}, 200);
await page("", { Authorization: `Bearer ${token}` }, 200);

const ok = await session(`${wssBase}/?token=${token}`, 3000, (ws) => {
  setTimeout(() => ws.send(new Uint8Array([1, 1, 0, 0, 0, 42])), 300);
});
console.log(`  wss with the token: opened ${ok.opened}, ops ${[...new Set(ok.ops)].join(",")}, ${ok.channels.length} channels`);
if (!ok.opened) fail(`wss with the token was not opened (${ok.error})`);
if (!ok.ops.includes("serverInfo") || !ok.ops.includes("advertise")) fail("wss with the token: no serverInfo or advertise");
if ((ok.capabilities ?? ["?"]).includes("clientPublish")) fail("serverInfo offers clientPublish");
if (!ok.channels.includes("bridge/scene")) fail("bridge/scene is not advertised");
if (!ok.statuses.some((s) => s.includes("read-only"))) fail(`a client message was not refused as read-only: ${ok.statuses.join(" | ")}`);

const none = await session(`${wssBase}/`, 2000);
console.log(`  wss without a token: opened ${none.opened}`);
if (none.opened) fail("wss without the token was opened");
const wrong = await session(`${wssBase}/?token=${token.slice(0, -1)}x`, 2000);
console.log(`  wss with a wrong token: opened ${wrong.opened}`);
if (wrong.opened) fail("wss with a wrong token was opened");
const plain = await session(`${base.replace(/^https:/, "ws:")}/?token=${token}`, 2000);
console.log(`  plain ws to the TLS port: opened ${plain.opened}`);
if (plain.opened) fail("plain ws (no TLS) was opened");

if (failures.length === 0) console.log("OK: only a client with the token is served, over TLS, read-only");
process.exit(failures.length ? 1 : 0);
