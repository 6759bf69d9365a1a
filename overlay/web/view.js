// Image <-> screen coordinates of the labelling page, without the DOM (tested with node --test).
//
// Two pixel conventions meet here. The browser's: image pixel i spans [i, i + 1), so its centre
// is at i + 0.5. OpenCV's, which the labels file stores: pixel centres at integers. A stored
// pixel is therefore the browser coordinate minus 0.5, at any zoom and any screen scaling.
//
// A view maps browser image coordinates to canvas (device) pixels: screen = image * scale + (x, y).

export const MIN_SCALE = 1 / 64;
export const MAX_SCALE = 64;

/** The view showing the whole image centred in a canvas of the given size. */
export function fitView(imageWidth, imageHeight, canvasWidth, canvasHeight) {
  const scale = clampScale(Math.min(canvasWidth / imageWidth, canvasHeight / imageHeight));
  return centred(scale, imageWidth, imageHeight, canvasWidth, canvasHeight);
}

/** The view at one image pixel per canvas pixel, centred. */
export function actualSizeView(imageWidth, imageHeight, canvasWidth, canvasHeight) {
  return centred(1, imageWidth, imageHeight, canvasWidth, canvasHeight);
}

function centred(scale, imageWidth, imageHeight, canvasWidth, canvasHeight) {
  return { scale, x: (canvasWidth - imageWidth * scale) / 2, y: (canvasHeight - imageHeight * scale) / 2 };
}

/** The scale kept within [MIN_SCALE, MAX_SCALE]. */
export function clampScale(scale) {
  return Math.min(MAX_SCALE, Math.max(MIN_SCALE, scale));
}

/** Canvas position of a browser image point. */
export function toScreen(view, [x, y]) {
  return [x * view.scale + view.x, y * view.scale + view.y];
}

/** Browser image point under a canvas position. */
export function toImage(view, [sx, sy]) {
  return [(sx - view.x) / view.scale, (sy - view.y) / view.scale];
}

/** The view zoomed by `factor` about a canvas position: the image point under it stays under it. */
export function zoomAbout(view, factor, [sx, sy]) {
  const scale = clampScale(view.scale * factor);
  const [ix, iy] = toImage(view, [sx, sy]);
  return { scale, x: sx - ix * scale, y: sy - iy * scale };
}

/** The view moved by (dx, dy) canvas pixels. */
export function panView(view, dx, dy) {
  return { scale: view.scale, x: view.x + dx, y: view.y + dy };
}

/** The stored (OpenCV) pixel of a browser image point. */
export function storedFromBrowser([x, y]) {
  return [x - 0.5, y - 0.5];
}

/** The browser image point of a stored (OpenCV) pixel. */
export function browserFromStored([u, v]) {
  return [u + 0.5, v + 0.5];
}

/** The stored pixel under a canvas position. */
export function storedAt(view, screen) {
  return storedFromBrowser(toImage(view, screen));
}

/** Canvas position of a stored pixel. */
export function screenOfStored(view, stored) {
  return toScreen(view, browserFromStored(stored));
}

/** A stored pixel moved by (du, dv) image pixels (arrow-key nudges), kept to 1e-6 px so that
 *  ten nudges of 0.1 px make exactly 1 px. */
export function nudge([u, v], du, dv) {
  const r = (a) => Math.round(a * 1e6) / 1e6;
  return [r(u + du), r(v + dv)];
}

/** Index of the point (stored pixels) nearest a canvas position within `radius` canvas pixels, or -1. */
export function pickNearest(view, points, screen, radius) {
  let best = -1;
  let bestDistance = radius;
  points.forEach((p, i) => {
    const [sx, sy] = screenOfStored(view, p);
    const d = Math.hypot(sx - screen[0], sy - screen[1]);
    if (d <= bestDistance) {
      best = i;
      bestDistance = d;
    }
  });
  return best;
}
