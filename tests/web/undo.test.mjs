// The labelling page's undo stack (overlay/web/undo.js).
import test from "node:test";
import assert from "node:assert/strict";
import { UndoStack } from "../../overlay/web/undo.js";

test("undo and redo walk the edits; a new edit drops what could be redone", () => {
  const s = new UndoStack({ labels: [] });
  assert.equal(s.canUndo, false);
  s.push({ labels: [{ name: "a" }] });
  s.push({ labels: [{ name: "a" }, { name: "b" }] });
  assert.deepEqual(s.undo(), { labels: [{ name: "a" }] });
  assert.deepEqual(s.undo(), { labels: [] });
  assert.equal(s.undo(), null);
  assert.deepEqual(s.redo(), { labels: [{ name: "a" }] });
  s.push({ labels: [{ name: "c" }] });
  assert.equal(s.canRedo, false);
  assert.equal(s.redo(), null);
  assert.deepEqual(s.current, { labels: [{ name: "c" }] });
});

test("states are copies, an edit that changes nothing is not recorded, the oldest go past the limit", () => {
  const doc = { labels: [{ name: "a", pixel: [1, 2] }] };
  const s = new UndoStack(doc, 3);
  doc.labels[0].pixel[0] = 99;  // the caller's object, not the stack's
  assert.equal(s.current.labels[0].pixel[0], 1);
  s.current.labels.push({ name: "x" });  // a copy as well
  assert.equal(s.current.labels.length, 1);
  assert.equal(s.push(s.current), false);
  for (let i = 0; i < 5; i += 1) s.push({ labels: [{ name: `n${i}` }] });
  assert.equal(s.states.length, 3);
  s.undo();
  s.undo();
  assert.equal(s.canUndo, false);
  assert.deepEqual(s.current, { labels: [{ name: "n2" }] });
});
