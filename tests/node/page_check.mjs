// Opens teleop_bridge's page (served by the bridge at /) in headless Chromium, driven over the
// DevTools protocol (Node's own WebSocket client, no npm package), waits for live frames, takes
// a screenshot and checks it.
//
//   node [--experimental-websocket] tests/node/page_check.mjs CHROMIUM http://127.0.0.1:PORT/ \
//        SCREENSHOT.png SECONDS
//
// Checks, each a failure with a message:
//  - the page drew more than 20 scene frames and received more than 20 plot messages (its
//    counters on <body data-*>), and drew triangles;
//  - the force trace moved: its samples span more than 0.05 N, and in the screenshot the
//    force plot's red trace covers more than 5 distinct rows;
//  - the scene canvas in the screenshot is not blank: more than 3 % of its pixels differ from
//    the background and their luminance varies (standard deviation over 5 of 255).
// Exit status 0 when all hold, 1 otherwise.
import { spawn } from "node:child_process";
import { mkdtempSync, readFileSync, writeFileSync, existsSync, rmSync } from "node:fs";
import { tmpdir } from "node:os";
import { join } from "node:path";
import { inflateSync } from "node:zlib";
import { failureList, requireWebSocket } from "./check_lib.mjs";

const [chromium, pageUrl, shotPath, secondsText] = process.argv.slice(2);
if (!chromium || !pageUrl || !shotPath || !secondsText) {
  console.error("usage: node page_check.mjs CHROMIUM URL SCREENSHOT.png SECONDS");
  process.exit(2);
}
requireWebSocket();
const { failures, fail } = failureList();
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

// ---- a small PNG reader (8-bit RGB/RGBA, not interlaced: what Chromium writes) ----
function readPng(buf) {
  let at = 8, width = 0, height = 0, colourType = 0, depth = 0;
  const idat = [];
  while (at < buf.length) {
    const len = buf.readUInt32BE(at), type = buf.toString("ascii", at + 4, at + 8);
    const data = buf.subarray(at + 8, at + 8 + len);
    if (type === "IHDR") {
      width = data.readUInt32BE(0);
      height = data.readUInt32BE(4);
      depth = data[8];
      colourType = data[9];
      if (data[12] !== 0) throw new Error("interlaced PNG");
    } else if (type === "IDAT") idat.push(data);
    at += 12 + len;
  }
  if (depth !== 8 || (colourType !== 2 && colourType !== 6)) throw new Error(`PNG depth ${depth} colour type ${colourType}`);
  const bpp = colourType === 6 ? 4 : 3, stride = width * bpp;
  const raw = inflateSync(Buffer.concat(idat));
  const px = Buffer.alloc(height * stride);
  for (let y = 0; y < height; y++) {
    const f = raw[y * (stride + 1)], src = y * (stride + 1) + 1, dst = y * stride;
    for (let x = 0; x < stride; x++) {
      const a = x >= bpp ? px[dst + x - bpp] : 0, b = y > 0 ? px[dst - stride + x] : 0;
      const c = x >= bpp && y > 0 ? px[dst - stride + x - bpp] : 0;
      let p = raw[src + x];
      if (f === 1) p += a;
      else if (f === 2) p += b;
      else if (f === 3) p += (a + b) >> 1;
      else if (f === 4) {
        const e = a + b - c, pa = Math.abs(e - a), pb = Math.abs(e - b), pc = Math.abs(e - c);
        p += pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
      }
      px[dst + x] = p & 255;
    }
  }
  return { width, height, pixel: (x, y) => { const i = y * stride + x * bpp; return [px[i], px[i + 1], px[i + 2]]; } };
}

// ---- Chromium over the DevTools protocol ----
const profile = mkdtempSync(join(tmpdir(), "teleop-page-"));
const browser = spawn(chromium, ["--headless=new", "--no-sandbox", "--use-angle=swiftshader",
  "--enable-unsafe-swiftshader", "--no-first-run", "--no-default-browser-check", "--disable-extensions",
  "--remote-debugging-port=0", `--user-data-dir=${profile}`, "--window-size=1280,800", "about:blank"],
  { stdio: ["ignore", "ignore", "pipe"] });
let browserLog = "";
browser.stderr.on("data", (d) => { browserLog = (browserLog + d).slice(-4000); });
const portFile = join(profile, "DevToolsActivePort");
// its start-up, not what is tested: up to 30 s (beyond 10 s seen once beside another test)
for (let i = 0; i < 300 && !existsSync(portFile); i++) await sleep(100);
if (!existsSync(portFile)) {
  console.error(`FAIL chromium did not start its DevTools endpoint:\n${browserLog}`);
  browser.kill();
  process.exit(1);
}
const [port, path] = readFileSync(portFile, "utf8").trim().split("\n");
const ws = new WebSocket(`ws://127.0.0.1:${port}${path}`);
await new Promise((resolve, reject) => { ws.onopen = resolve; ws.onerror = reject; });
let nextId = 1;
const pending = new Map();
ws.onmessage = (ev) => {
  const m = JSON.parse(ev.data);
  if (m.id && pending.has(m.id)) {
    const { resolve, reject } = pending.get(m.id);
    pending.delete(m.id);
    if (m.error) reject(new Error(m.error.message));
    else resolve(m.result);
  }
};
const send = (method, params = {}, sessionId) => new Promise((resolve, reject) => {
  const id = nextId++;
  pending.set(id, { resolve, reject });
  ws.send(JSON.stringify({ id, method, params, ...(sessionId ? { sessionId } : {}) }));
});

let status = 1;
try {
  const { targetId } = await send("Target.createTarget", { url: "about:blank" });
  const { sessionId } = await send("Target.attachToTarget", { targetId, flatten: true });
  const page = (method, params) => send(method, params, sessionId);
  await page("Emulation.setDeviceMetricsOverride", { width: 1280, height: 800, deviceScaleFactor: 1, mobile: false });
  await page("Page.navigate", { url: pageUrl });
  const evaluate = async (expr) => (await page("Runtime.evaluate", { expression: expr, returnByValue: true })).result.value;
  let state = {};
  const deadline = Date.now() + Number(secondsText) * 1000;
  while (Date.now() < deadline) {
    await sleep(500);
    state = (await evaluate("document.body ? Object.assign({}, document.body.dataset) : {}")) ?? {};
    if (Number(state.drawnFrames) > 20 && Number(state.plotMessages) > 20 && Number(state.forceMax) - Number(state.forceMin) > 0.05) break;
  }
  console.log(`  page state: ${JSON.stringify(state)}`);
  if (!(Number(state.drawnFrames) > 20)) fail(`the page drew ${state.drawnFrames} scene frames (more than 20 expected)`);
  if (!(Number(state.plotMessages) > 20)) fail(`the page received ${state.plotMessages} plot messages (more than 20 expected)`);
  if (!(Number(state.triangles) > 0)) fail("the page drew no triangle");
  if (!(Number(state.forceMax) - Number(state.forceMin) > 0.05)) fail(`the force trace did not move: ${state.forceMin}-${state.forceMax} N`);
  const rects = await evaluate(`JSON.stringify(["scene", "force"].map((id) => { const r = document.getElementById(id).getBoundingClientRect(); return [r.x, r.y, r.width, r.height].map(Math.round); }))`);
  const shot = await page("Page.captureScreenshot", { format: "png" });
  const png = Buffer.from(shot.data, "base64");
  writeFileSync(shotPath, png);
  const img = readPng(png);
  const [scene, force] = JSON.parse(rects);
  checkScene(img, scene);
  checkForceTrace(img, force);
  status = failures.length ? 1 : 0;
} catch (e) {
  fail(`DevTools: ${e.message}`);
} finally {
  ws.close();
  browser.kill();
  await sleep(200);
  rmSync(profile, { recursive: true, force: true });
}

function checkScene(img, [x0, y0, w, h]) {
  const bg = [18, 19, 23];
  let differ = 0, n = 0, sum = 0, sum2 = 0;
  for (let y = y0; y < Math.min(img.height, y0 + h); y += 2)
    for (let x = x0; x < Math.min(img.width, x0 + w); x += 2) {
      const p = img.pixel(x, y), lum = 0.3 * p[0] + 0.59 * p[1] + 0.11 * p[2];
      n++; sum += lum; sum2 += lum * lum;
      if (Math.abs(p[0] - bg[0]) + Math.abs(p[1] - bg[1]) + Math.abs(p[2] - bg[2]) > 30) differ++;
    }
  const sd = Math.sqrt(Math.max(0, sum2 / n - (sum / n) ** 2));
  console.log(`  scene canvas: ${((100 * differ) / n).toFixed(1)} % of pixels drawn, luminance sd ${sd.toFixed(1)}`);
  if (!(differ > 0.03 * n)) fail(`the scene canvas is blank: ${differ} of ${n} pixels drawn`);
  if (!(sd > 5)) fail(`the scene canvas is flat: luminance sd ${sd.toFixed(1)}`);
}

function checkForceTrace(img, [x0, y0, w, h]) {
  const rows = new Set();
  for (let y = y0; y < Math.min(img.height, y0 + h); y++)
    for (let x = x0 + 40; x < Math.min(img.width, x0 + w); x++) {
      const p = img.pixel(x, y);
      if (p[0] > 180 && p[1] < 130 && p[2] < 130) rows.add(y);
    }
  console.log(`  force plot: the trace covers ${rows.size} rows`);
  if (rows.size <= 5) fail(`the force trace is flat or missing in the screenshot: ${rows.size} rows`);
}

if (failures.length === 0) console.log(`OK: the page drew the scene and a moving force trace (${shotPath})`);
process.exit(status);
