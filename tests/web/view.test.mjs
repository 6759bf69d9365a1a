// The labelling page's coordinate maths (overlay/web/view.js): OpenCV's pixel convention, zoom
// about the cursor, nudges, picking.
import test from "node:test";
import assert from "node:assert/strict";
import * as V from "../../overlay/web/view.js";

test("a stored pixel is the browser coordinate minus one half, both ways", () => {
  assert.deepEqual(V.storedFromBrowser([10.5, 20.5]), [10, 20]);  // the centre of browser pixel 10
  assert.deepEqual(V.browserFromStored([0, 0]), [0.5, 0.5]);
  for (const p of [[0.25, 7.75], [-0.5, -0.5], [1279.49, 719.5], [123.456789, 0.1 + 0.2]])
    assert.deepEqual(V.storedFromBrowser(V.browserFromStored(p)), p.map((x) => x + 0.5 - 0.5));
});

test("the stored pixel under the cursor does not depend on zoom or screen scaling", () => {
  // The image point (OpenCV) 100.25, 50.75 seen at several zooms and device pixel ratios.
  const stored = [100.25, 50.75];
  for (const scale of [0.1, 1, 3, 16, 64])
    for (const offset of [[0, 0], [-4000.5, 37.25]]) {
      const view = { scale, x: offset[0], y: offset[1] };
      const screen = V.screenOfStored(view, stored);
      const back = V.storedAt(view, screen);
      assert.ok(Math.abs(back[0] - stored[0]) < 1e-9 && Math.abs(back[1] - stored[1]) < 1e-9, `${scale}: ${back}`);
    }
  // At 16x the centre of browser pixel 100 spans 16 canvas pixels; its middle is stored 100.
  const view = { scale: 16, x: 0, y: 0 };
  assert.deepEqual(V.storedAt(view, [100.5 * 16, 7.5 * 16]), [100, 7]);
});

test("zoom keeps the image point under the cursor and stays within its limits", () => {
  let view = V.fitView(1280, 720, 800, 600);
  assert.equal(view.scale, 800 / 1280);
  const cursor = [333, 222];
  const before = V.toImage(view, cursor);
  for (let i = 0; i < 40; i += 1) view = V.zoomAbout(view, 1.25, cursor);
  assert.equal(view.scale, V.MAX_SCALE);
  const after = V.toImage(view, cursor);
  assert.ok(Math.abs(after[0] - before[0]) < 1e-9 && Math.abs(after[1] - before[1]) < 1e-9);
  for (let i = 0; i < 100; i += 1) view = V.zoomAbout(view, 0.5, cursor);
  assert.equal(view.scale, V.MIN_SCALE);
});

test("fit and 1:1 centre the image", () => {
  const f = V.fitView(1000, 500, 800, 800);
  assert.deepEqual(f, { scale: 0.8, x: 0, y: 200 });
  assert.deepEqual(V.actualSizeView(100, 50, 300, 150), { scale: 1, x: 100, y: 50 });
});

test("ten nudges of 0.1 px are exactly 1 px", () => {
  let p = [10, 20];
  for (let i = 0; i < 10; i += 1) p = V.nudge(p, 0.1, -0.1);
  assert.deepEqual(p, [11, 19]);
});

test("picking takes the nearest point within the radius, in canvas pixels", () => {
  const view = { scale: 2, x: 0, y: 0 };
  const points = [[10, 10], [12, 10], [100, 100]];
  assert.equal(V.pickNearest(view, points, V.screenOfStored(view, [11.6, 10]), 8), 1);
  assert.equal(V.pickNearest(view, points, V.screenOfStored(view, [50, 50]), 8), -1);
});
