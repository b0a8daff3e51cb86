// N WebSocket clients of teleop_bridge in one Node process, each subscribed to every advertised
// channel and reading everything, for tests/bench/bridge_clients.sh. Prints one line:
// "clients N opened K messages M bytes B".
//   node [--experimental-websocket] bridge_clients.mjs ws://127.0.0.1:PORT N SECONDS
const [url, nText, secondsText] = process.argv.slice(2);
const n = Number(nText);
let opened = 0, messages = 0, bytes = 0;
const sockets = [];
for (let i = 0; i < n; i++) {
  const ws = new WebSocket(url, ["foxglove.websocket.v1"]);
  ws.binaryType = "arraybuffer";
  ws.onopen = () => opened++;
  ws.onmessage = (ev) => {
    if (typeof ev.data === "string") {
      const m = JSON.parse(ev.data);
      if (m.op === "advertise") {
        ws.send(JSON.stringify({ op: "subscribe", subscriptions: m.channels.map((c) => ({ id: c.id, channelId: c.id })) }));
      }
      return;
    }
    messages++;
    bytes += ev.data.byteLength;
  };
  sockets.push(ws);
}
await new Promise((r) => setTimeout(r, Number(secondsText) * 1000));
for (const ws of sockets) ws.close();
console.log(`clients ${n} opened ${opened} messages ${messages} bytes ${bytes}`);
process.exit(0);
