// End to end in a real browser: `kccd calib label` serves the page, Debian's chromium (driven by
// playwright-core, headless) labels the demo's points as an operator would (a world point typed
// in, a body point found by search, then a click on the frame), a click on the drawn volumes offers
// that body's nearest point first, saves, and the residual table the page shows must match
// `kccd calib --json` on the saved file. A screenshot is kept. Then "snap to the robot": four
// rough clicks that do not solve, a robot mask drawn by `kccd render --mask`, the box ticked: the
// page shows the snapped pose and both outlines (screenshot label_page_snap.png), unticked it goes
// back.
//   node label_page.mjs KCCD DATA_DIR OUT_DIR
// Exit 0 passed, 1 failed (also when no browser can start: never skipped).
import { spawn, execFileSync } from "node:child_process";
import { mkdirSync, rmSync, existsSync, readFileSync, writeFileSync } from "node:fs";
import { join } from "node:path";
import { createInterface } from "node:readline";
import { chromium } from "playwright-core";

const [kccd, data, out] = process.argv.slice(2);
if (!out) {
  console.error("usage: node label_page.mjs KCCD DATA_DIR OUT_DIR");
  process.exit(1);
}
rmSync(out, { recursive: true, force: true });
mkdirSync(out, { recursive: true });
const fail = (why) => {
  console.error(`label_page: ${why}`);
  process.exitCode = 1;
};

// `kccd calib label ARGS` started, and the address it prints first.
async function serve(args) {
  const server = spawn(kccd, ["calib", "label", ...args], { stdio: ["ignore", "pipe", "inherit"] });
  const url = await new Promise((resolve, reject) => {
    createInterface({ input: server.stdout }).once("line", resolve);
    server.once("exit", (code) => reject(new Error(`kccd calib label exited with ${code} before printing its URL`)));
  });
  return { server, url };
}

// Headless chromium on `url`, the page ready; its uncaught errors collected in `errors`.
async function openPage(url) {
  const browser = await chromium.launch({ executablePath: "/usr/bin/chromium", headless: true,
    args: ["--no-sandbox", "--disable-background-networking", "--disable-gpu"] });
  // bypassCSP: the page's policy forbids eval, which Playwright's waitForFunction uses.
  const context = await browser.newContext({ viewport: { width: 1600, height: 900 }, bypassCSP: true });
  const page = await context.newPage();
  const errors = [];
  page.on("pageerror", (e) => errors.push(e.message));
  page.on("dialog", (d) => d.accept());  // "Quit without saving?": yes
  await page.goto(url);
  await page.waitForSelector("body[data-ready='1']", { timeout: 20000 });
  return { browser, page, errors };
}

// The server's exit status once it has stopped (it is sent SIGTERM half a second from now).
async function stopped(server) {
  setTimeout(() => server.kill("SIGTERM"), 500);
  return server.exitCode !== null ? server.exitCode : await new Promise((resolve) => server.once("exit", (c) => resolve(c)));
}

// The frame: the demo arm rendered at the labels' state (what the camera sees, on grey).
const frame = join(out, "frame.png");
execFileSync(kccd, ["render", join(data, "demo_arm.yaml"), "--camera", join(data, "demo_camera.yaml"), "--state", "0.3,0.4,0.6",
  "--no-legend", "-o", frame]);
const labels = join(out, "labels.yaml");
const camera = join(out, "camera.yaml");
const { server, url } = await serve(["--intrinsics", join(data, "demo_camera.yaml"), "--image", frame, "--labels", labels,
  "--model", join(data, "demo_arm.yaml"), "--state", "0.3,0.4,0.6", "-o", camera, "-q"]);
if (!/^http:\/\/127\.0\.0\.1:\d+\/$/.test(url)) fail(`first line is not the URL: ${url}`);

// The demo's labels (data/demo_labels.yaml): world points typed in; the shoulder's core point
// through the target search.
const wanted = [
  { name: "pedestal_0", pixel: [548.6, 444.3], world: [0, 0, 0] },
  { name: "pedestal_1", pixel: [545.4, 354.0], world: [0, 0, 0.25] },
  { name: "table_0", pixel: [527.3, 539.1], world: [0.45, -0.4, 0.1] },
  { name: "table_1", pixel: [704.6, 656.5], world: [0.95, -0.4, 0.1] },
  { name: "table_2", pixel: [963.9, 495.6], world: [0.95, 0.4, 0.1] },
  { name: "table_3", pixel: [788.9, 420.4], world: [0.45, 0.4, 0.1] },
  { name: "post_0", pixel: [718.1, 538.7], world: [0.6, 0, 0] },
];

let browser;
try {
  let page, errors;
  ({ browser, page, errors } = await openPage(url));
  const settle = () => page.waitForFunction(() => !window.kccdPage.pending(), null, { timeout: 20000 });
  for (const w of wanted) {
    await page.click("#worldform summary").catch(() => {});
    await page.evaluate(() => (document.getElementById("worldform").open = true));
    await page.fill("#wname", w.name);
    await page.fill("#wx", String(w.world[0]));
    await page.fill("#wy", String(w.world[1]));
    await page.fill("#wz", String(w.world[2]));
    await page.click("#wuse");
    const [x, y] = await page.evaluate((p) => window.kccdPage.clientOf(p), w.pixel);
    await page.mouse.click(x, y);
    await settle();
  }
  await page.fill("#search", "shoulder point 0");
  await page.press("#search", "Enter");
  const [sx, sy] = await page.evaluate(() => window.kccdPage.clientOf([544.4, 316.6]));
  await page.mouse.click(sx, sy);
  await settle();
  // A point placed on the drawn volumes offers the body there first, its nearest point first.
  const probe = await page.evaluate(async () => {
    const s = await (await fetch("/api/session")).json();
    for (const m of s.candidates.model_points) {
      // Away from the labels placed: a click there would select the label.
      if (s.labels.labels.some((l) => Math.hypot(l.pixel[0] - m.pixel[0], l.pixel[1] - m.pixel[1]) < 30)) continue;
      const p = await (await fetch(`/api/pick?x=${m.pixel[0]}&y=${m.pixel[1]}`)).json();
      if (p.body === m.body) return m;
    }
    return null;
  });
  if (!probe) fail("no model point shows its own body in the drawn volumes");
  else {
    const [px, py] = await page.evaluate((p) => window.kccdPage.clientOf(p), probe.pixel);
    await page.mouse.click(px, py);
    await page.waitForFunction(() => document.getElementById("picked").textContent !== "", null, { timeout: 20000 });
    const first = await page.$eval("#targets li", (li) => li.textContent);
    if (!first.startsWith(`${probe.body} point ${probe.point} `)) fail(`clicked on ${probe.name}'s volume; the first target offered is '${first}'`);
    await page.keyboard.press("Escape");
  }

  await page.keyboard.press("Control+s");
  await page.waitForFunction(() => document.getElementById("message").textContent.startsWith("saved"), null, { timeout: 20000 });
  await page.screenshot({ path: join(out, "label_page.png") });

  // The page's residual table against kccd calib --json on the saved file.
  const table = await page.$$eval("#labels tbody tr", (rows) => rows.map((r) => [r.cells[1].textContent, r.cells[3].textContent]));
  if (table.length !== wanted.length + 1) fail(`the table has ${table.length} rows, expected ${wanted.length + 1}`);
  if (!existsSync(labels)) fail("Save wrote no labels file");
  let cli = null;
  try {
    cli = JSON.parse(execFileSync(kccd, ["calib", "--intrinsics", join(data, "demo_camera.yaml"), "--labels", labels, "--model",
      join(data, "demo_arm.yaml"), "--state", "0.3,0.4,0.6", "-o", join(out, "cli_camera.yaml"), "--json"]).toString());
  } catch (e) {
    cli = JSON.parse(e.stdout.toString());  // not solvable is exit 4, with its JSON
  }
  for (const [name, shown] of table) {
    const r = cli.residuals.find((x) => x.name === name);
    if (!r) fail(`${name}: not in kccd calib's residuals`);
    else if (shown !== (r.px === null ? "behind" : Number(r.px).toFixed(2))) fail(`${name}: the page shows ${shown} px, kccd calib ${r.px}`);
  }
  const solve = await page.evaluate(() => window.kccdPage.solve());
  if (solve.status !== cli.status) fail(`page status ${solve.status}, kccd calib ${cli.status}`);
  if (cli.status === "solved" && !existsSync(camera)) fail("solved, but Save wrote no camera file");
  if (cli.status === "solved" && readFileSync(camera, "utf8") !== readFileSync(join(out, "cli_camera.yaml"), "utf8"))
    fail("the page's camera file differs from kccd calib's on the same labels");
  if (errors.length) fail(`errors in the page: ${errors.join("; ")}`);
  const ms = (await page.evaluate(() => window.kccdPage.refreshMs())).sort((a, b) => a - b);
  if (!ms.length) fail("no edit was solved");
  console.log(`label_page: edit -> solve and volumes shown: median ${ms[ms.length >> 1].toFixed(0)} ms, max ${ms[ms.length - 1].toFixed(0)} ms over ${ms.length} edits`);
  console.log(`label_page: ${table.length} labels placed in ${url}, status ${cli.status}, rms ${cli.reprojection_rms_px} px; ` +
    `screenshot ${join(out, "label_page.png")}`);
  await page.click("#quit");
} catch (e) {
  fail(e.stack || String(e));
} finally {
  if (browser) await browser.close();
}
const code = await stopped(server);
if (code !== 0) fail(`kccd calib label exited with ${code}`);

// Snap to the robot.
const mask = join(out, "mask.png");
execFileSync(kccd, ["render", join(data, "demo_arm.yaml"), "--camera", join(data, "demo_camera.yaml"), "--state", "0.3,0.4,0.6",
  "--mask", "-o", mask]);
const rough = join(out, "rough.yaml");
writeFileSync(rough, `labels:
  - {name: pedestal_0, pixel: [554.6, 444.3], world: [0, 0, 0]}
  - {name: table_1, pixel: [704.6, 650.5], world: [0.95, -0.4, 0.1]}
  - {name: upper_arm_1, pixel: [671.0, 368.5], body: upper_arm, point: [0.4, 0, 0]}
  - {name: gripper_3, pixel: [767.9, 525.5], body: gripper, point: [0.42, 0.04, 0]}
`);
const { server: snapServer, url: snapUrl } = await serve(["--intrinsics", join(data, "demo_camera.yaml"), "--image", frame,
  "--labels", rough, "--model", join(data, "demo_arm.yaml"), "--state", "0.3,0.4,0.6", "--masks", mask, "-q"]);
let browser2;
try {
  let page, errors;
  ({ browser: browser2, page, errors } = await openPage(snapUrl));
  if (await page.$eval("#snapbox", (e) => e.hidden)) fail("with --masks the page offers no snap");
  const before = await page.evaluate(() => window.kccdPage.solve().status);
  if (before === "solved") fail("four clicks solved without the snap: the test shows nothing");
  await page.check("#snap");
  await page.waitForFunction(() => window.kccdPage.solve().snap.on && !document.getElementById("snap").disabled, null, { timeout: 60000 });
  const snapped = await page.evaluate(() => window.kccdPage.solve());
  if (snapped.status !== "solved") fail(`snapped: status ${snapped.status} (${snapped.snap.message})`);
  const figures = await page.$eval("#figures", (e) => e.textContent);
  if (!figures.includes("snapped to the masks: IoU")) fail(`the figures do not say the snap: ${figures}`);
  await page.screenshot({ path: join(out, "label_page_snap.png") });
  await page.uncheck("#snap");
  await page.waitForFunction(() => !window.kccdPage.solve().snap.on && !document.getElementById("snap").disabled, null, { timeout: 60000 });
  if ((await page.evaluate(() => window.kccdPage.solve().status)) !== before) fail("unticked, the solve is not the points' again");
  if (errors.length) fail(`errors in the page: ${errors.join("; ")}`);
  console.log(`label_page: snapped from 4 clicks: IoU ${snapped.refinement.frames[0].iou_before.toFixed(3)} -> ` +
    `${snapped.refinement.frames[0].iou_after.toFixed(3)}; screenshot ${join(out, "label_page_snap.png")}`);
  await page.click("#quit");
} catch (e) {
  fail(e.stack || String(e));
} finally {
  if (browser2) await browser2.close();
}
const code2 = await stopped(snapServer);
if (code2 !== 0) fail(`kccd calib label --masks exited with ${code2}`);
