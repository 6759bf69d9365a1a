// The labelling page's document edits and targets (overlay/web/labels.js).
import test from "node:test";
import assert from "node:assert/strict";
import * as L from "../../overlay/web/labels.js";

const session = {
  layout: [{ id: 3, size: 0.1, corners: [[0, 0, 0], [0.1, 0, 0], [0.1, 0.1, 0], [0, 0.1, 0]] }],
  bodies: [
    { name: "pedestal", world_fixed: true, points: [[0, 0, 0], [0, 0, 0.25]] },
    { name: "forearm", world_fixed: false, points: [[0, 0, 0], [0.3, 0, 0]] },
  ],
};

test("a target gives a label with the file's fields and a unique name", () => {
  let doc = L.emptyDocument();
  const targets = L.targetsOf(session);
  const corner = targets.find((t) => t.name === "tag3.c1");
  const body = targets.find((t) => t.name === "forearm.1");
  const fixed = targets.find((t) => t.name === "pedestal.1");
  doc = L.addLabel(doc, L.labelFor(doc, [10.25, 20.5], corner));
  doc = L.addLabel(doc, L.labelFor(doc, [30, 40], body));
  doc = L.addLabel(doc, L.labelFor(doc, [31, 41], body));
  doc = L.addLabel(doc, L.labelFor(doc, [5, 6], fixed));
  assert.deepEqual(doc.labels, [
    { name: "tag3.c1", pixel: [10.25, 20.5], world: [0.1, 0, 0] },
    { name: "forearm.1", pixel: [30, 40], body: "forearm", point: [0.3, 0, 0] },
    { name: "forearm.1_2", pixel: [31, 41], body: "forearm", point: [0.3, 0, 0] },
    { name: "pedestal.1", pixel: [5, 6], world: [0, 0, 0.25] },
  ]);
  // What the server stores comes back the same through JSON (the file's numbers round-trip).
  assert.deepEqual(JSON.parse(JSON.stringify(doc)), doc);
});

test("move, remove and disable leave the input document alone", () => {
  const doc = { labels: [{ name: "a", pixel: [1, 2], world: [0, 0, 0] }, { name: "b", pixel: [3, 4], world: [1, 0, 0] }] };
  const moved = L.moveLabel(doc, "a", [1.5, 2.5]);
  assert.deepEqual(moved.labels[0].pixel, [1.5, 2.5]);
  assert.deepEqual(doc.labels[0].pixel, [1, 2]);
  assert.deepEqual(L.removeLabel(doc, "a").labels.map((l) => l.name), ["b"]);
  assert.deepEqual(L.enabledOnly(doc, new Set(["b"])).labels.map((l) => l.name), ["a"]);
  assert.equal(doc.labels.length, 2);
});

test("search matches every word, in names and descriptions", () => {
  const targets = L.targetsOf(session);
  assert.deepEqual(L.searchTargets(targets, "tag 3 corner 2").map((t) => t.name), ["tag3.c2"]);
  assert.deepEqual(L.searchTargets(targets, "FOREARM").map((t) => t.name), ["forearm.0", "forearm.1"]);
  assert.equal(L.searchTargets(targets, "").length, targets.length);
});

test("a pick puts the body's points first, nearest first, and keeps every target once", () => {
  const targets = L.targetsOf(session);
  const pick = { body: "forearm", points: [{ name: "forearm.1", distance_px: 2.5 }, { name: "forearm.0", distance_px: 40 }] };
  const ordered = L.pickedFirst(targets, pick);
  assert.deepEqual(ordered.slice(0, 2).map((t) => t.name), ["forearm.1", "forearm.0"]);
  assert.ok(ordered[0].picked && ordered[0].text.endsWith("· 2.5 px"));
  assert.equal(ordered.length, targets.length);
  assert.deepEqual(new Set(ordered.map((t) => t.name)), new Set(targets.map((t) => t.name)));
  assert.deepEqual(ordered[0].point, [0.3, 0, 0], "the target itself is unchanged");
  assert.equal(L.pickedFirst(targets, { body: null, points: [] }), targets);
  assert.equal(L.pickedFirst(targets, null), targets);
});
