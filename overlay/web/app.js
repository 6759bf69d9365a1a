// The labelling page of `kccd calib label`: frames, points and their targets, the live solve and
// the volumes at the estimate. All maths lives in view.js, labels.js and undo.js; this file binds
// them to the DOM and to the server's API (GET /api/session, PUT /api/labels, POST /api/save).
import * as V from "/view.js";
import * as L from "/labels.js";
import { UndoStack } from "/undo.js";

const $ = (id) => document.getElementById(id);
const canvas = $("canvas");
const ctx = canvas.getContext("2d");
const loupe = $("loupe");
const lctx = loupe.getContext("2d");

const state = {
  session: null,
  frame: 0,
  images: [],        // per frame: HTMLImageElement
  overlays: [],      // per frame: {rev, image}
  stacks: [],        // per frame: UndoStack of labels documents
  disabled: [],      // per frame: Set of names left out of the solve
  view: { scale: 1, x: 0, y: 0 },
  solve: null,
  selected: null,    // label name
  pending: null,     // stored pixel placed, waiting for a target
  target: null,      // the chosen target
  targets: [],
  sort: { key: "name", dir: 1 },
  dirty: false,
  mouse: null,       // canvas position
  drag: null,        // {mode: "pan"|"move"|"maybe", start, view, name}
  space: false,
  revision: 0,
  preview: null,
  pick: null,        // GET /api/pick's answer for the pending point
  refreshMs: [],     // per edit, the time until its solve and volumes were shown
};

const doc = () => state.preview || state.stacks[state.frame].current;  // preview: a label being dragged
const frameInfo = () => state.session.frames[state.frame];
const dpr = () => window.devicePixelRatio || 1;

function message(text, error = false) {
  $("message").textContent = text;
  $("message").className = error ? "error" : "";
}

async function api(method, path, body) {
  const res = await fetch(path, {
    method,
    headers: body === undefined ? {} : { "Content-Type": "application/json" },
    body: body === undefined ? undefined : JSON.stringify(body),
  });
  const json = await res.json().catch(() => ({ error: `HTTP ${res.status}` }));
  if (!res.ok) throw new Error(json.error || `HTTP ${res.status}`);
  return json;
}

function loadImage(src) {
  return new Promise((resolve, reject) => {
    const img = new Image();
    img.onload = () => resolve(img);
    img.onerror = () => reject(new Error(`cannot load ${src}`));
    img.src = src;
  });
}

// ---- drawing

function resize() {
  const r = canvas.getBoundingClientRect();
  canvas.width = Math.round(r.width * dpr());
  canvas.height = Math.round(r.height * dpr());
  draw();
}

function fit() {
  const f = frameInfo();
  state.view = V.fitView(f.width, f.height, canvas.width, canvas.height);
  draw();
}

function actualSize() {
  const f = frameInfo();
  state.view = V.actualSizeView(f.width, f.height, canvas.width, canvas.height);
  draw();
}

function residualsOfFrame() {
  const out = new Map();
  if (!state.solve) return out;
  const prefix = state.session.frames.length > 1 ? `f${state.frame + 1}/` : "";
  for (const r of state.solve.residuals || []) {
    if (r.frame !== undefined && r.frame !== state.frame) continue;
    const name = r.name.startsWith(prefix) ? r.name.slice(prefix.length) : r.name;
    out.set(name, r);
  }
  return out;
}

function marker(c, [x, y], colour, size, selected) {
  c.strokeStyle = "#000";
  c.lineWidth = 3 * dpr();
  c.beginPath();
  c.arc(x, y, size, 0, 2 * Math.PI);
  c.stroke();
  c.strokeStyle = colour;
  c.lineWidth = (selected ? 2.5 : 1.5) * dpr();
  c.beginPath();
  c.arc(x, y, size, 0, 2 * Math.PI);
  c.moveTo(x - size * 1.6, y);
  c.lineTo(x - size * 0.4, y);
  c.moveTo(x + size * 0.4, y);
  c.lineTo(x + size * 1.6, y);
  c.moveTo(x, y - size * 1.6);
  c.lineTo(x, y - size * 0.4);
  c.moveTo(x, y + size * 0.4);
  c.lineTo(x, y + size * 1.6);
  c.stroke();
}

function draw() {
  if (!state.session) return;
  const img = state.images[state.frame];
  ctx.setTransform(1, 0, 0, 1, 0, 0);
  ctx.fillStyle = "#111";
  ctx.fillRect(0, 0, canvas.width, canvas.height);
  ctx.imageSmoothingEnabled = state.view.scale < 1;  // crisp pixels when zoomed in
  const f = frameInfo();
  const { scale, x, y } = state.view;
  if (img) ctx.drawImage(img, x, y, f.width * scale, f.height * scale);
  const ov = state.overlays[state.frame];
  if ($("volumes").checked && ov && ov.image) {
    ctx.globalAlpha = $("opacity").value / 100;
    ctx.drawImage(ov.image, x, y, f.width * scale, f.height * scale);
    ctx.globalAlpha = 1;
  }
  const size = 6 * dpr();
  const residuals = residualsOfFrame();
  const magnify = 20;
  // Detected tags: their corners as small squares (placed tags are points by themselves).
  for (const tag of f.candidates.tags) {
    ctx.strokeStyle = tag.placed ? "#3c3" : "#eb3";
    ctx.lineWidth = 1 * dpr();
    ctx.beginPath();
    tag.corners.forEach((c, k) => {
      const [sx, sy] = V.screenOfStored(state.view, c);
      if (k === 0) ctx.moveTo(sx, sy);
      else ctx.lineTo(sx, sy);
    });
    ctx.closePath();
    ctx.stroke();
  }
  for (const l of doc().labels) {
    const off = state.disabled[state.frame].has(l.name);
    const r = residuals.get(l.name);
    const rejected = r && !r.inlier;
    const s = V.screenOfStored(state.view, l.pixel);
    if (r && r.projected && !off) {
      // The residual, magnified for inliers (rejected: to scale), from where it was seen.
      const m = rejected ? 1 : magnify;
      const p = [l.pixel[0] + (r.projected[0] - l.pixel[0]) * m, l.pixel[1] + (r.projected[1] - l.pixel[1]) * m];
      const e = V.screenOfStored(state.view, p);
      ctx.strokeStyle = rejected ? "#e44" : "#4af";
      ctx.lineWidth = 1.5 * dpr();
      ctx.beginPath();
      ctx.moveTo(s[0], s[1]);
      ctx.lineTo(e[0], e[1]);
      ctx.stroke();
    }
    marker(ctx, s, off ? "#777" : rejected ? "#e44" : "#ff3", size, l.name === state.selected);
    ctx.font = `${11 * dpr()}px system-ui`;
    ctx.fillStyle = off ? "#999" : rejected ? "#f66" : "#fff";
    ctx.fillText(l.name, s[0] + size * 1.8, s[1] - size * 0.8);
  }
  if (state.pending) marker(ctx, V.screenOfStored(state.view, state.pending), "#f0f", size, true);
  drawLoupe();
}

function drawLoupe() {
  const img = state.images[state.frame];
  lctx.imageSmoothingEnabled = false;
  lctx.fillStyle = "#000";
  lctx.fillRect(0, 0, loupe.width, loupe.height);
  if (!img || !state.mouse) return;
  const [bx, by] = V.toImage(state.view, state.mouse);
  const span = 18;  // image pixels across: 10x
  const k = loupe.width / span;
  lctx.drawImage(img, bx - span / 2, by - span / 2, span, span, 0, 0, loupe.width, loupe.height);
  lctx.strokeStyle = "#f0f";
  lctx.lineWidth = 1;
  lctx.beginPath();
  lctx.moveTo(loupe.width / 2, 0);
  lctx.lineTo(loupe.width / 2, loupe.height);
  lctx.moveTo(0, loupe.height / 2);
  lctx.lineTo(loupe.width, loupe.height / 2);
  lctx.stroke();
  for (const l of doc().labels) {
    const [u, v] = V.browserFromStored(l.pixel);
    const lx = (u - (bx - span / 2)) * k, ly = (v - (by - span / 2)) * k;
    if (lx < 0 || ly < 0 || lx > loupe.width || ly > loupe.height) continue;
    lctx.strokeStyle = "#ff3";
    lctx.strokeRect(lx - 4, ly - 4, 8, 8);
  }
}

// ---- the panel

function renderTargets() {
  const list = $("targets");
  list.replaceChildren();
  const shown = offeredTargets();
  $("picked").textContent = state.pick && state.pick.body ? `on the volumes: ${state.pick.body}, its points nearest first` : "";
  for (const t of shown.slice(0, 200)) {
    const li = document.createElement("li");
    li.textContent = t.text;
    li.title = t.kind === "world" ? `world ${t.world.join(", ")}` : `${t.body} ${t.point.join(", ")}`;
    li.setAttribute("role", "option");
    li.className = [state.target && state.target.name === t.name ? "chosen" : "", t.picked ? "picked" : ""].join(" ").trim();
    li.onclick = () => chooseTarget(t);
    list.appendChild(li);
  }
}

// The targets offered: the search's matches, the body under the placed point first.
const offeredTargets = () => L.searchTargets(L.pickedFirst(state.targets, state.pick), $("search").value);

// Which body the volumes show where the point was placed, and its points nearest first.
async function pickAt(pixel) {
  state.pick = null;
  try {
    const [x, y] = pixel;
    const pick = await api("GET", `/api/pick?frame=${state.frame}&x=${x}&y=${y}`);
    if (state.pending === pixel) state.pick = pick;  // still the point placed
  } catch (e) {
    message(e.message, true);
  }
  renderTargets();
}

function chooseTarget(t) {
  state.target = t;
  if (state.pending) {
    const label = L.labelFor(doc(), state.pending, t);
    state.selected = label.name;
    edit(L.addLabel(doc(), label));
    state.pending = null;
    state.pick = null;
    $("pending").hidden = true;
    state.target = null;
    $("search").value = "";  // the search found this label's target; the next starts afresh
  }
  renderTargets();
  draw();
}

function renderSolve() {
  const s = state.solve;
  if (!s) return;
  const solved = s.status === "solved";
  $("verdict").className = `verdict ${solved ? "solved" : "unsolved"}`;
  $("verdict").textContent = solved ? "Solved" : `Not solved (${s.status})`;
  const n = (v, d = 3) => (v === null || v === undefined ? "–" : Number(v).toPrecision(d));
  let text = s.message || "";
  // The message already says the inliers, RMS and sigmas in kccd calib's words; added here: how far
  // the volumes may be off in the image, and who was rejected.
  if (solved && s.volume_sigma_px != null) text += `\nthe volumes: ±${n(s.volume_sigma_px)} px (1 σ, worst core point)`;
  if (s.rejected && s.rejected.length) text += `\nrejected: ${s.rejected.join(", ")}`;
  // Snapping to the robot masks: whether it is on, and what it did (IoU per frame before -> after).
  const snap = s.snap || { available: false, on: false };
  $("snapbox").hidden = !snap.available;
  $("snap").checked = snap.on;
  if (snap.on) {
    const r = s.refinement;
    if (r && r.improved)
      text += `\nsnapped to the masks: IoU ${r.frames.map((f) => `${n(f.iou_before)} → ${n(f.iou_after)}`).join(", ")}` +
        `\n(yellow: the mask's outline, magenta: the drawn robot's)`;
    else text += `\nnot snapped: ${snap.message}`;
  }
  $("figures").textContent = text;
}

// Snap on or off: one request at a time with the label edits (an edit made meanwhile is sent
// after it, as resolve() does), the box disabled until the answer is shown.
async function setSnap(on) {
  $("snap").disabled = true;
  while (inflight) await inflight.catch(() => {});
  $("stale").hidden = false;
  inflight = api("POST", "/api/snap", { on });
  try {
    state.solve = await inflight;
    state.revision = state.solve.revision;
    state.dirty = true;  // Save writes another camera now
    message("");
    await refreshOverlay(state.frame);
  } catch (e) {
    message(e.message, true);
  } finally {
    $("snap").disabled = false;
    settled();
  }
}

function renderLabels() {
  const residuals = residualsOfFrame();
  const rows = doc().labels.map((l) => ({ l, r: residuals.get(l.name), off: state.disabled[state.frame].has(l.name) }));
  const { key, dir } = state.sort;
  const value = (row) =>
    key === "px" ? (row.r ? row.r.px ?? Infinity : -1) : key === "on" ? (row.off ? 1 : 0) : key === "target" ? L.describeTarget(row.l) : row.l.name;
  rows.sort((a, b) => (value(a) < value(b) ? -dir : value(a) > value(b) ? dir : 0));
  const body = $("labels").tBodies[0];
  body.replaceChildren();
  for (const { l, r, off } of rows) {
    const tr = document.createElement("tr");
    tr.className = [l.name === state.selected ? "selected" : "", r && !r.inlier ? "rejected" : "", off ? "off" : ""].join(" ");
    const on = document.createElement("input");
    on.type = "checkbox";
    on.checked = !off;
    on.title = "use this label (unchecked: kept, left out of the solve and the file)";
    on.onchange = () => {
      if (on.checked) state.disabled[state.frame].delete(l.name);
      else state.disabled[state.frame].add(l.name);
      resolve();
    };
    const del = document.createElement("button");
    del.textContent = "×";
    del.title = "delete";
    del.onclick = () => edit(L.removeLabel(doc(), l.name));
    const cells = [on, l.name, L.describeTarget(l), r ? (r.px === null ? "behind" : Number(r.px).toFixed(2)) : "", del];
    cells.forEach((c, i) => {
      const td = document.createElement("td");
      if (i === 1) td.className = "name";
      if (c instanceof Node) td.appendChild(c);
      else td.textContent = c;
      tr.appendChild(td);
    });
    tr.onclick = (e) => {
      if (e.target.tagName === "INPUT" || e.target.tagName === "BUTTON") return;
      state.selected = l.name;
      renderLabels();
      draw();
    };
    body.appendChild(tr);
  }
  $("count").textContent = `${doc().labels.length} in this frame`;
  $("undo").disabled = !state.stacks[state.frame].canUndo;
  $("redo").disabled = !state.stacks[state.frame].canRedo;
}

// ---- edits and the server

function edit(next) {
  if (!state.stacks[state.frame].push(next)) return;
  state.dirty = true;
  resolve();
}

let inflight = null;
let again = false;
async function resolve() {
  renderLabels();
  draw();
  if (inflight) {
    again = true;  // one more solve when this one is back: the latest edit wins
    return;
  }
  $("stale").hidden = false;
  const started = performance.now();
  const frame = state.frame;
  inflight = api("PUT", `/api/labels?frame=${frame}`, L.enabledOnly(doc(), state.disabled[frame]));
  try {
    state.solve = await inflight;
    state.revision = state.solve.revision;
    message("");
    await refreshOverlay(frame);
    state.refreshMs.push(performance.now() - started);  // edit to solve and volumes shown
  } catch (e) {
    message(e.message, true);
  } finally {
    settled();
  }
}

// A request to the server has ended (answered or not): the page shows the solve it has, and the
// edit made meanwhile, if any, is sent now.
function settled() {
  inflight = null;
  $("stale").hidden = true;
  renderSolve();
  renderLabels();
  draw();
  if (again) {
    again = false;
    resolve();
  }
}

async function refreshOverlay(frame) {
  const ov = state.overlays[frame];
  if (ov && ov.rev === state.revision) return;
  try {
    const image = await loadImage(`/overlay/${frame}.png?rev=${state.revision}`);
    state.overlays[frame] = { rev: state.revision, image };
  } catch (e) {
    message(e.message, true);
  }
}

async function save() {
  try {
    const saved = await api("POST", "/api/save", {});
    state.dirty = false;
    message(`saved ${saved.labels.join(", ") || "no labels"}` + (saved.camera ? `; camera ${saved.camera}` : "") +
      (saved.backups.length ? `\nprevious versions kept as ${saved.backups.join(", ")}` : ""));
  } catch (e) {
    message(e.message, true);
  }
}

function undo() {
  const d = state.stacks[state.frame].undo();
  if (d) {
    state.dirty = true;
    resolve();
  }
}

function redo() {
  const d = state.stacks[state.frame].redo();
  if (d) {
    state.dirty = true;
    resolve();
  }
}

// ---- input

function canvasPoint(e) {
  const r = canvas.getBoundingClientRect();
  return [(e.clientX - r.left) * dpr(), (e.clientY - r.top) * dpr()];
}

function labelAt(screen) {
  const labels = doc().labels;
  const i = V.pickNearest(state.view, labels.map((l) => l.pixel), screen, 8 * dpr());
  return i < 0 ? null : labels[i].name;
}

canvas.addEventListener("pointerdown", (e) => {
  canvas.focus();
  canvas.setPointerCapture(e.pointerId);
  const p = canvasPoint(e);
  const name = e.button === 0 && !state.space ? labelAt(p) : null;
  if (name) {
    state.selected = name;
    state.drag = { mode: "move", start: p, name, moved: false, base: state.stacks[state.frame].current };
  } else if (e.button === 1 || state.space) {
    state.drag = { mode: "pan", start: p, view: state.view };
  } else if (e.button === 0) {
    state.drag = { mode: "maybe", start: p, view: state.view };
  }
  renderLabels();
  draw();
});

canvas.addEventListener("pointermove", (e) => {
  const p = canvasPoint(e);
  state.mouse = p;
  const [u, v] = V.storedAt(state.view, p);
  $("cursor").textContent = `x ${u.toFixed(2)}  y ${v.toFixed(2)}  ·  ${Math.round(state.view.scale * 100)} %`;
  const d = state.drag;
  if (d) {
    const dx = p[0] - d.start[0], dy = p[1] - d.start[1];
    if (d.mode === "maybe" && Math.hypot(dx, dy) > 4 * dpr()) d.mode = "pan";
    if (d.mode === "pan") state.view = V.panView(d.view, dx, dy);
    if (d.mode === "move") {
      d.moved = true;
      d.pixel = V.storedAt(state.view, p);
      state.preview = L.moveLabel(d.base, d.name, d.pixel);  // shown at once, recorded when released
    }
  }
  draw();
});

canvas.addEventListener("pointerup", (e) => {
  const d = state.drag;
  state.drag = null;
  if (!d) return;
  if (d.mode === "maybe") {
    // A click: place a point; with a target chosen, the label is made at once.
    const pixel = V.storedAt(state.view, canvasPoint(e));
    if (state.target) {
      state.pending = pixel;
      chooseTarget(state.target);
    } else {
      state.pending = pixel;
      state.selected = null;
      $("pending").hidden = false;
      $("search").focus();
      draw();
      pickAt(pixel);
    }
  } else if (d.mode === "move" && d.moved) {
    state.preview = null;
    edit(L.moveLabel(d.base, d.name, d.pixel));
  }
});

canvas.addEventListener("wheel", (e) => {
  e.preventDefault();
  const factor = Math.pow(1.0015, -e.deltaY * (e.deltaMode === 1 ? 33 : 1));
  state.view = V.zoomAbout(state.view, factor, canvasPoint(e));
  draw();
}, { passive: false });

canvas.addEventListener("pointerleave", () => {
  state.mouse = null;
  drawLoupe();
});

window.addEventListener("keydown", (e) => {
  const ctrl = e.ctrlKey || e.metaKey;
  if (e.target.tagName === "INPUT" && e.key !== "Escape" && !(ctrl && e.key === "s")) return;
  if (ctrl && (e.key === "z" || e.key === "Z")) {
    e.preventDefault();
    if (e.shiftKey) redo();
    else undo();
  } else if (ctrl && e.key === "y") {
    e.preventDefault();
    redo();
  } else if (ctrl && e.key === "s") {
    e.preventDefault();
    save();
  } else if (e.key === "Escape") {
    state.pending = null;
    state.pick = null;
    renderTargets();
    canvas.focus();
    state.selected = null;
    $("pending").hidden = true;
    renderLabels();
    draw();
  } else if ((e.key === "Delete" || e.key === "Backspace") && state.selected) {
    e.preventDefault();
    edit(L.removeLabel(doc(), state.selected));
    state.selected = null;
  } else if (e.key.startsWith("Arrow")) {
    e.preventDefault();
    const step = e.shiftKey ? 1 : 0.1;
    const [dx, dy] = { ArrowLeft: [-1, 0], ArrowRight: [1, 0], ArrowUp: [0, -1], ArrowDown: [0, 1] }[e.key];
    const l = doc().labels.find((x) => x.name === state.selected);
    if (l) edit(L.moveLabel(doc(), l.name, V.nudge(l.pixel, dx * step, dy * step)));
    else {
      state.view = V.panView(state.view, -dx * 40 * dpr(), -dy * 40 * dpr());
      draw();
    }
  } else if (e.key === " ") {
    state.space = true;
    e.preventDefault();
  } else if (e.key === "f" || e.key === "F") fit();
  else if (e.key === "1") actualSize();
  else if (e.key === "v" || e.key === "V") {
    $("volumes").checked = !$("volumes").checked;
    draw();
  } else if (e.key === "?") $("keys").showModal();
});
window.addEventListener("keyup", (e) => {
  if (e.key === " ") state.space = false;
});
window.addEventListener("beforeunload", (e) => {
  if (state.dirty) {
    e.preventDefault();
    e.returnValue = "";
  }
});
window.addEventListener("resize", resize);

$("search").addEventListener("input", renderTargets);
$("search").addEventListener("keydown", (e) => {
  if (e.key === "Enter") {
    const first = offeredTargets()[0];
    if (first) chooseTarget(first);
  }
});
$("wuse").onclick = () => {
  const xyz = ["wx", "wy", "wz"].map((id) => Number($(id).value));
  const name = $("wname").value.trim();
  if (!name || xyz.some((v) => !Number.isFinite(v) || $("wx").value === "")) return message("a world point needs a name and x, y, z in metres", true);
  chooseTarget({ kind: "world", name, world: xyz, text: `${name} (world)` });
};
$("fit").onclick = fit;
$("actual").onclick = actualSize;
$("volumes").onchange = draw;
$("opacity").oninput = draw;
$("undo").onclick = undo;
$("redo").onclick = redo;
$("save").onclick = save;
$("help").onclick = () => $("keys").showModal();
$("quit").onclick = async () => {
  if (state.dirty && !confirm("Quit without saving the last edits?")) return;
  await api("POST", "/api/quit", {}).catch(() => {});
  state.dirty = false;
  message("the server has ended: this page can be closed");
};
$("frame").onchange = async () => {
  state.frame = Number($("frame").value);
  state.selected = null;
  state.pending = null;
  state.pick = null;
  showRecovered();
  fit();
  await refreshOverlay(state.frame);
  renderLabels();
  draw();
};
for (const th of $("labels").tHead.rows[0].cells)
  if (th.dataset.sort)
    th.onclick = () => {
      state.sort = { key: th.dataset.sort, dir: state.sort.key === th.dataset.sort ? -state.sort.dir : 1 };
      renderLabels();
    };

// An autosave newer than the labels file (edits a session made and nobody saved): offered as an
// edit that can be undone.
function showRecovered() {
  const r = state.session.frames[state.frame].recovered;
  $("recovered").hidden = !r;
  if (r) $("recovered-text").textContent = `${r.file} holds ${r.labels.labels.length} label(s) autosaved after the labels file was last saved.`;
}
$("snap").onchange = () => setSnap($("snap").checked);
$("restore").onclick = () => {
  const f = state.session.frames[state.frame];
  if (!f.recovered) return;
  edit(f.recovered.labels);
  f.recovered = null;
  showRecovered();
};

// ---- start

async function start() {
  try {
    const s = await api("GET", "/api/session");
    state.session = s;
    state.solve = s.solve;
    state.revision = s.revision;
    state.targets = L.targetsOf(s);
    state.stacks = s.frames.map((f) => new UndoStack(f.labels));
    state.disabled = s.frames.map(() => new Set());
    state.images = await Promise.all(s.frames.map((f) => loadImage(f.image)));
    for (const f of s.frames) {
      const o = document.createElement("option");
      o.value = f.index;
      o.textContent = `frame ${f.index + 1}: ${f.name}`;
      $("frame").appendChild(o);
    }
    document.title = `kccd calib label — ${s.frames[0].labels_file}`;
    resize();
    fit();
    renderTargets();
    renderSolve();
    renderLabels();
    showRecovered();
    await refreshOverlay(0);
    draw();
    document.body.dataset.ready = "1";  // for tests
    // For tests and scripts driving the page: where a stored pixel is on the page (CSS pixels).
    window.kccdPage = {
      clientOf(stored) {
        const [sx, sy] = V.screenOfStored(state.view, stored);
        const r = canvas.getBoundingClientRect();
        return [r.left + sx / dpr(), r.top + sy / dpr()];
      },
      solve: () => state.solve,
      pending: () => inflight !== null || again,
      refreshMs: () => [...state.refreshMs],
    };
  } catch (e) {
    message(e.message, true);
  }
}
start();
