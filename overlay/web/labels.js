// The labels document the page edits ({labels: [{name, pixel, world} | {name, pixel, body,
// point, state?}]}, the labels file's fields) and the targets a point can be given, without the
// DOM (tested with node --test). Every function returns a new document.

const copy = (value) => JSON.parse(JSON.stringify(value));

/** An empty document. */
export function emptyDocument() {
  return { labels: [] };
}

/** `base` if no label has it, else base_2, base_3, ... */
export function uniqueName(doc, base) {
  const names = new Set(doc.labels.map((l) => l.name));
  if (!names.has(base)) return base;
  for (let k = 2; ; k += 1) if (!names.has(`${base}_${k}`)) return `${base}_${k}`;
}

/** The label a target gives a pixel. Targets: {kind: "world", name, world: [x, y, z]} or
 *  {kind: "body", name, body, point: [x, y, z]}; the name is made unique in `doc`. */
export function labelFor(doc, pixel, target) {
  const label = { name: uniqueName(doc, target.name), pixel: [pixel[0], pixel[1]] };
  if (target.kind === "body") {
    label.body = target.body;
    label.point = [...target.point];
  } else {
    label.world = [...target.world];
  }
  return label;
}

/** The document with `label` added at the end. */
export function addLabel(doc, label) {
  const out = copy(doc);
  out.labels.push(copy(label));
  return out;
}

/** The document with label `name` at `pixel`. */
export function moveLabel(doc, name, pixel) {
  const out = copy(doc);
  const l = out.labels.find((x) => x.name === name);
  if (l) l.pixel = [pixel[0], pixel[1]];
  return out;
}

/** The document without label `name`. */
export function removeLabel(doc, name) {
  const out = copy(doc);
  out.labels = out.labels.filter((x) => x.name !== name);
  return out;
}

/** The document without the labels whose names are in `disabled` (a Set): what is solved and saved. */
export function enabledOnly(doc, disabled) {
  return { ...copy(doc), labels: doc.labels.filter((l) => !disabled.has(l.name)).map(copy) };
}

/** What a label shows, in words. */
export function describeTarget(label) {
  const f = (v) => v.map((x) => Number(x.toFixed(4))).join(", ");
  return label.body !== undefined ? `${label.body} (${f(label.point)})` : `world (${f(label.world)})`;
}

/** Every target the session offers, searchable: layout tag corners (world points), the model's
 *  body points, and the model points the estimate projects. */
export function targetsOf(session) {
  const targets = [];
  for (const tag of session.layout || [])
    tag.corners.forEach((c, k) => targets.push({ kind: "world", name: `tag${tag.id}.c${k}`, world: c, text: `tag ${tag.id} corner ${k}` }));
  for (const body of session.bodies || [])
    body.points.forEach((p, k) =>
      targets.push(
        body.world_fixed
          ? { kind: "world", name: `${body.name}.${k}`, world: p, text: `${body.name} point ${k} (fixed)` }
          : { kind: "body", name: `${body.name}.${k}`, body: body.name, point: p, text: `${body.name} point ${k}` },
      ),
    );
  return targets;
}

/** The targets whose text or name contains every word of `query` (case-insensitive). */
export function searchTargets(targets, query) {
  const words = query.toLowerCase().split(/\s+/).filter(Boolean);
  return targets.filter((t) => words.every((w) => `${t.name} ${t.text}`.toLowerCase().includes(w)));
}

/** The targets in the order a click on the volumes suggests: the picked body's points nearest
 *  first (from GET /api/pick: {body, points: [{name, distance_px}]}), each saying how far, then
 *  the rest as they were. No body picked: `targets` unchanged. */
export function pickedFirst(targets, pick) {
  if (!pick || !pick.body) return targets;
  const byName = new Map(targets.map((t) => [t.name, t]));
  const first = [];
  for (const p of pick.points || []) {
    const t = byName.get(p.name);
    if (!t) continue;
    first.push({ ...t, text: `${t.text} · ${Number(p.distance_px).toFixed(1)} px`, picked: true });
    byName.delete(p.name);
  }
  return [...first, ...targets.filter((t) => byName.has(t.name))];
}
