// Opens a run in the open-source Foxglove Studio web build (npm @foxglove/studio-base 1.48.0,
// with react and react-dom 17) in headless Chromium (Debian's `chromium`), with the shipped
// layout imported the way a user does it (Layouts -> Import from file). Asserts that the
// run's topics appear with their schemas and the layout's panels show, and saves a
// screenshot.
//
// Usage: node replay.mjs RUN.mcap LAYOUT.json SCREENSHOT.png
//        node replay.mjs --live PORT LAYOUT.json SCREENSHOT.png -- COMMAND [ARGS...]
// The second form opens Studio's Foxglove WebSocket connection to ws://127.0.0.1:PORT, then
// starts COMMAND (a paced `uncoil run --live`), and asserts that messages keep arriving while
// it runs and that it exits with 0.
//
// Studio 1.48 offers the WebSocket subprotocol `foxglove.websocket.v1`; the Foxglove SDK's
// server accepts only `foxglove.sdk.v1`, which Foxglove states is the same protocol under a
// new name (github.com/orgs/foxglove/discussions/1131; Lichtblick, a fork of Studio, added the
// name in its pull request 819). In live mode this page offers the new name in place of the
// old one, in the page and in Studio's socket worker, and changes nothing else.
// Env: CHROMIUM (default /usr/bin/chromium), NODE_MODULES (default ./node_modules).
import fs from "node:fs";
import http from "node:http";
import path from "node:path";
import { spawn } from "node:child_process";
import { fileURLToPath } from "node:url";

const here = path.dirname(fileURLToPath(import.meta.url));
const modules = process.env.NODE_MODULES ?? path.join(here, "node_modules");
const { chromium } = await import(path.join(modules, "playwright-core", "index.mjs"));

const args = process.argv.slice(2);
const live = args[0] === "--live";
const livePort = live ? Number(args[1]) : 0;
const [mcapPath, layoutPath, shotPath] = live ? ["", args[2], args[3]] : args;
const command = live ? args.slice(args.indexOf("--") + 1) : [];
if (!layoutPath || !shotPath || (live && (!livePort || args.indexOf("--") < 0 || !command.length))) {
  console.error("usage: node replay.mjs RUN.mcap LAYOUT.json SCREENSHOT.png\n" +
    "       node replay.mjs --live PORT LAYOUT.json SCREENSHOT.png -- COMMAND [ARGS...]");
  process.exit(2);
}

/** Offers the Foxglove SDK's name of the WebSocket protocol in place of Studio 1.48's. */
const SUBPROTOCOL_SHIM = `(() => {
  const Native = self.WebSocket, OLD = "foxglove.websocket.v1", SDK = "foxglove.sdk.v1";
  self.WebSocket = class extends Native {
    constructor(url, protocols) {
      const offered = [].concat(protocols ?? []);
      super(url, offered.includes(OLD) ? [SDK, ...offered.filter((p) => p !== OLD)] : protocols);
    }
    get protocol() { return super.protocol === SDK ? OLD : super.protocol; }
  };
})();
`;

const files = {
  "/": [path.join(here, "index.html"), "text/html"],
  "/boot.js": [path.join(here, "boot.js"), "text/javascript"],
  "/react.js": [path.join(modules, "react/umd/react.production.min.js"), "text/javascript"],
  "/react-dom.js": [
    path.join(modules, "react-dom/umd/react-dom.production.min.js"),
    "text/javascript",
  ],
};
if (!live) {
  files["/run.mcap"] = [path.resolve(mcapPath), "application/octet-stream"];
}
const studio = path.join(modules, "@foxglove/studio-base/assets");
const types = { ".js": "text/javascript", ".wasm": "application/wasm", ".png": "image/png",
  ".ttf": "font/ttf", ".json": "application/json" };

/** A static server that answers HTTP Range requests, as the remote data source needs. */
function serve(req, res) {
  const url = new URL(req.url, "http://localhost");
  let entry = files[url.pathname];
  if (!entry && url.pathname.startsWith("/studio/")) {
    const file = path.join(studio, path.normalize(url.pathname.slice("/studio/".length)));
    if (file.startsWith(studio)) {
      entry = [file, types[path.extname(file)] ?? "application/octet-stream"];
    }
  }
  if (!entry || !fs.existsSync(entry[0])) {
    res.writeHead(404).end();
    return;
  }
  const [file, type] = entry;
  if (live && type === "text/javascript") {
    const text = fs.readFileSync(file, "utf8");
    if (text.includes("new WebSocket(data.wsUrl, data.protocols)")) {
      // Studio's socket worker.
      res.writeHead(200, { "Content-Type": type, "Cache-Control": "no-store" });
      res.end(SUBPROTOCOL_SHIM + text);
      return;
    }
  }
  const size = fs.statSync(file).size;
  const headers = {
    "Content-Type": type,
    "Accept-Ranges": "bytes",
    "Access-Control-Allow-Origin": "*",
    "Cache-Control": "no-store",
  };
  const range = /^bytes=(\d*)-(\d*)$/.exec(req.headers.range ?? "");
  if (range) {
    let start = range[1] === "" ? size - Number(range[2]) : Number(range[1]);
    let end = range[1] === "" || range[2] === "" ? size - 1 : Number(range[2]);
    end = Math.min(end, size - 1);
    if (start > end || start < 0) {
      res.writeHead(416, { "Content-Range": `bytes */${size}` }).end();
      return;
    }
    res.writeHead(206, { ...headers, "Content-Range": `bytes ${start}-${end}/${size}`,
      "Content-Length": end - start + 1 });
    if (req.method === "HEAD") {
      res.end();
    } else {
      fs.createReadStream(file, { start, end }).pipe(res);
    }
    return;
  }
  res.writeHead(200, { ...headers, "Content-Length": size });
  if (req.method === "HEAD") {
    res.end();
  } else {
    fs.createReadStream(file).pipe(res);
  }
}

const server = http.createServer(serve);
await new Promise((resolve) => server.listen(0, "127.0.0.1", resolve));
const base = `http://127.0.0.1:${server.address().port}`;

const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM ?? "/usr/bin/chromium",
  headless: true,
  args: ["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
    "--ignore-gpu-blocklist"],
});
let failed = false;
let child = null;
let exited = null;
try {
  const page = await browser.newPage({ viewport: { width: 1600, height: 900 } });
  page.on("pageerror", (err) => console.error("page error:", err.message));
  page.on("response", (res) => {
    if (res.status() >= 400) {
      console.error(`HTTP ${res.status()} ${res.url()}`);
    }
  });
  page.on("console", (msg) => {
    if (msg.type() === "error" || process.env.DEBUG_CONSOLE) {
      console.error("console:", msg.text().slice(0, 300));
    }
  });
  // The layout import asks for a file with window.showOpenFilePicker; answer with the layout.
  const layoutText = fs.readFileSync(layoutPath, "utf8");
  const layoutName = path.basename(layoutPath);
  await page.addInitScript(([text, name]) => {
    window.showOpenFilePicker = async () => [
      { getFile: async () => new File([text], name, { type: "application/json" }) },
    ];
  }, [layoutText, layoutName]);

  if (live) {
    // The run goes first and does not wait: Studio connects while it runs, a late viewer.
    child = spawn(command[0], command.slice(1), { stdio: ["ignore", "ignore", "inherit"] });
    exited = new Promise((resolve) => child.on("exit", (code) => resolve(code)));
    console.log(`started: ${command.join(" ")}`);
    await page.addInitScript(SUBPROTOCOL_SHIM);
    const wsUrl = encodeURIComponent(`ws://127.0.0.1:${livePort}`);
    await page.goto(`${base}/?ds=foxglove-websocket&ds.url=${wsUrl}`);
    // A live source lists its topics under a tab of the data source's sidebar.
    const tab = page.getByRole("tab", { name: "Topics" });
    await tab.waitFor({ timeout: 120000 });
    await tab.click();
  } else {
    const dsUrl = encodeURIComponent(`${base}/run.mcap`);
    await page.goto(`${base}/?ds=remote-file&ds.url=${dsUrl}`);
  }

  // The data source's topic list shows every channel of the run with its schema.
  const expected = [
    ["/scene", "foxglove.SceneUpdate"],
    ["/state", "uncoil.State"],
    ["/events", "uncoil.Event"],
  ];
  for (const [topic, schema] of expected) {
    await page.getByText(topic, { exact: true }).first().waitFor({ timeout: live ? 30000 : 120000 });
    await page.getByText(schema, { exact: true }).first().waitFor({ timeout: 10000 });
    console.log(`topic ${topic} (${schema}) listed`);
  }
  // The data source's sidebar icon carries a badge with the count of player problems (a
  // schema it cannot parse, a chunk it cannot read).
  const checkProblems = async (when) => {
    const badge = await page.locator('[data-sidebar-key="connection"] .MuiBadge-badge')
      .innerText().catch(() => "");
    if (badge.trim() !== "") {
      throw new Error(`${when}: the data source reports ${badge.trim()} problem(s)`);
    }
  };
  await checkProblems("after loading");

  // Layouts -> Import layout, answered with the shipped layout file.
  await page.locator('[data-sidebar-key="layouts"]').click();
  await page.getByRole("button", { name: "Import layout" }).click();
  const name = path.basename(layoutName, ".json");
  await page.getByText(name, { exact: true }).first().waitFor({ timeout: 20000 });
  console.log(`layout ${name} imported`);
  // Close the sidebar to give the panels the room, then play to just before the bang.
  await page.locator('[data-sidebar-key="layouts"]').click();
  await page.waitForTimeout(2000);
  for (const title of ["coil radius r", "contact-line speed", "energy ledger", "floor forces",
    "final bang"]) {
    await page.getByText(title).first().waitFor({ timeout: 20000 });
  }
  console.log("panels of the layout shown");
  // Dismiss the 3D panel's first-use hint.
  const hint = page.getByText("Open settings to configure topics and layers.");
  if (await hint.count()) {
    await hint.locator("xpath=..").getByRole("button").first().click().catch(() => {});
  }
  if (live) {
    // Messages keep arriving while the run goes: the /events panel's latest message (its
    // receipt time and fields) changes.
    const latest = page.getByText(/uncoil\.Event @/).first();
    const shown = [];
    for (let k = 0; k < 3; k++) {
      shown.push((await latest.innerText({ timeout: 20000 }).catch(() => "?")).trim());
      await page.waitForTimeout(2000);
    }
    console.log(`latest /events message shown: ${shown.join(" -> ")}`);
    if (shown.includes("?") || new Set(shown).size < 3) {
      throw new Error(`no new /events message while the run went: ${shown.join(", ")}`);
    }
    await checkProblems("while live");
  } else {
    // Seek into the unroll by clicking the time bar at SEEK_FRACTION of its length (default
    // 0.84: about 2.04 s of the yoga mat's 2.44 s).
    const fraction = Number(process.env.SEEK_FRACTION ?? "0.84");
    const bar = await page.locator('[data-testid="PlaybackTime-text"]').boundingBox();
    const viewport = page.viewportSize();
    const scrubY = bar ? bar.y - 24 : viewport.height - 57;
    await page.mouse.click(10 + fraction * (viewport.width - 20), scrubY);
    await page.waitForTimeout(8000);
    const clock = page.locator('[data-testid="PlaybackTime-text"] input');
    console.log(`seeked to ${await clock.inputValue().catch(() => "?")}`);
    await checkProblems("after seeking");
  }
  await page.screenshot({ path: shotPath });
  console.log(`screenshot: ${shotPath}`);
  if (live) {
    const code = await exited;
    console.log(`the run exited with ${code}`);
    if (code !== 0) {
      throw new Error(`the live run exited with ${code}`);
    }
  }
} catch (err) {
  failed = true;
  console.error(err);
  // What the page showed when it failed, beside the screenshot it would have taken.
  const failedShot = shotPath.replace(/\.png$/, "") + "-failed.png";
  await browser.contexts()[0]?.pages()[0]?.screenshot({ path: failedShot }).catch(() => {});
  console.error(`the page as it failed: ${failedShot}`);
} finally {
  if (child && child.exitCode === null) {
    child.kill("SIGINT");
  }
  await browser.close();
  server.close();
}
process.exit(failed ? 1 : 0);
