// Checks shared by the Node tests on decoded teleop messages (bridge_check.mjs, mcap_check.mjs).

// Calls fail(text) for every field whose name contains "force" and holds a number that is not
// finite, at any depth of the decoded message.
export function checkFiniteForces(value, topic, fail, path = "") {
  if (value === null || typeof value !== "object") return;
  for (const [key, v] of Object.entries(value)) {
    if (/force/.test(key) && (typeof v === "number" || ArrayBuffer.isView(v) || Array.isArray(v))) {
      const values = typeof v === "number" ? [v] : Array.from(v);
      if (!values.every((x) => typeof x !== "number" || Number.isFinite(x))) {
        fail(`${topic}: ${path}${key} is not finite: ${values}`);
      }
    } else if (typeof v === "object") {
      checkFiniteForces(v, topic, fail, `${path}${key}.`);
    }
  }
}
