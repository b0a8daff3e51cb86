// Shared by the bridge checks: Node's WebSocket must be there, and failures are collected and
// printed (up to `printLimit` of them) so that a check can report every one at its end.
export function requireWebSocket() {
  if (typeof WebSocket !== "function") {
    console.error("FAIL this Node.js has no WebSocket: run it with --experimental-websocket (Node >= 20.10)");
    process.exit(1);
  }
}

export function failureList(printLimit = Infinity) {
  const failures = [];
  const fail = (what) => {
    if (failures.length < printLimit) console.error(`FAIL ${what}`);
    failures.push(what);
  };
  return { failures, fail };
}
