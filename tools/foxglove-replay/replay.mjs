// Replays a run.mcap in the open-source Foxglove Studio web build (npm @foxglove/studio-base
// 1.48.0, with react and react-dom 17) in headless Chromium (Debian's `chromium`), with the
// shipped layout imported the way a user does it (Layouts -> Import from file). Asserts that
// the run's topics appear and saves a screenshot.
//
// Usage: node replay.mjs RUN.mcap LAYOUT.json SCREENSHOT.png
// Env: CHROMIUM (default /usr/bin/chromium), NODE_MODULES (default ./node_modules).
import fs from "node:fs";
import http from "node:http";
import path from "node:path";
import { fileURLToPath } from "node:url";

const here = path.dirname(fileURLToPath(import.meta.url));
const modules = process.env.NODE_MODULES ?? path.join(here, "node_modules");
const { chromium } = await import(path.join(modules, "playwright-core", "index.mjs"));

const [mcapPath, layoutPath, shotPath] = process.argv.slice(2);
if (!mcapPath || !layoutPath || !shotPath) {
  console.error("usage: node replay.mjs RUN.mcap LAYOUT.json SCREENSHOT.png");
  process.exit(2);
}

const files = {
  "/": [path.join(here, "index.html"), "text/html"],
  "/boot.js": [path.join(here, "boot.js"), "text/javascript"],
  "/react.js": [path.join(modules, "react/umd/react.production.min.js"), "text/javascript"],
  "/react-dom.js": [
    path.join(modules, "react-dom/umd/react-dom.production.min.js"),
    "text/javascript",
  ],
  "/run.mcap": [path.resolve(mcapPath), "application/octet-stream"],
};
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
try {
  const page = await browser.newPage({ viewport: { width: 1600, height: 900 } });
  page.on("pageerror", (err) => console.error("page error:", err.message));
  page.on("response", (res) => {
    if (res.status() >= 400) {
      console.error(`HTTP ${res.status()} ${res.url()}`);
    }
  });
  page.on("console", (msg) => {
    if (msg.type() === "error") {
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

  const dsUrl = encodeURIComponent(`${base}/run.mcap`);
  await page.goto(`${base}/?ds=remote-file&ds.url=${dsUrl}`);

  // The data source's topic list shows every channel of the run with its schema.
  const expected = [
    ["/scene", "foxglove.SceneUpdate"],
    ["/state", "uncoil.State"],
    ["/events", "uncoil.Event"],
  ];
  for (const [topic, schema] of expected) {
    await page.getByText(topic, { exact: true }).first().waitFor({ timeout: 120000 });
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
  // Dismiss the 3D panel's first-use hint, then seek into the unroll by clicking the time
  // bar at SEEK_FRACTION of its length (default 0.84: about 2.04 s of the yoga mat's 2.44 s).
  const hint = page.getByText("Open settings to configure topics and layers.");
  if (await hint.count()) {
    await hint.locator("xpath=..").getByRole("button").first().click().catch(() => {});
  }
  const fraction = Number(process.env.SEEK_FRACTION ?? "0.84");
  const bar = await page.locator('[data-testid="PlaybackTime-text"]').boundingBox();
  const viewport = page.viewportSize();
  const scrubY = bar ? bar.y - 24 : viewport.height - 57;
  await page.mouse.click(10 + fraction * (viewport.width - 20), scrubY);
  await page.waitForTimeout(8000);
  const shown = await page.locator('[data-testid="PlaybackTime-text"] input').inputValue()
    .catch(() => "?");
  console.log(`seeked to ${shown}`);
  await checkProblems("after seeking");
  await page.screenshot({ path: shotPath });
  console.log(`screenshot: ${shotPath}`);
} catch (err) {
  failed = true;
  console.error(err);
} finally {
  await browser.close();
  server.close();
}
process.exit(failed ? 1 : 0);
