// The preview's orthographic camera, shared by the page (which turns it) and the worker
// that draws (renderer.js): yaw about Z, pitch about the screen's x, roll in the screen
// plane, then a scale (pixels per unit) and a pan (units).

export const CAMERAS = {
  top: [0, 0, 0], front: [0, -Math.PI / 2, 0], side: [-Math.PI / 2, -Math.PI / 2, 0],
  iso: [-Math.PI / 4, -0.96, 0], lathe: [Math.PI, -Math.PI / 2, -Math.PI / 2],
};

export function newView() {
  return { yaw: CAMERAS.iso[0], pitch: CAMERAS.iso[1], roll: 0, scale: 1, x: 0, y: 0 };
}

// The two rows of the rotation: screen x and y (before pan and zoom) of a point.
export function rotation(view) {
  const { yaw, pitch, roll } = view;
  const cy = Math.cos(yaw), sy = Math.sin(yaw), cp = Math.cos(pitch), sp = Math.sin(pitch);
  const cr = Math.cos(roll), sr = Math.sin(roll);
  return [
    [cr * cy - sr * cp * sy, -cr * sy - sr * cp * cy, sr * sp],
    [sr * cy + cr * cp * sy, -sr * sy + cr * cp * cy, -cr * sp],
  ];
}

export function project(view, x, y, z) {
  const [a, b] = rotation(view);
  return [a[0] * x + a[1] * y + a[2] * z, b[0] * x + b[1] * y + b[2] * z];
}

// Scale and pan that put ``bounds`` ([xmin, ymin, zmin, xmax, ymax, zmax]) in the middle of
// a ``width`` x ``height`` pixel view, at 85 % of it.
export function fitted(view, bounds, width, height) {
  let [minX, minY, maxX, maxY] = [Infinity, Infinity, -Infinity, -Infinity];
  const box = bounds || [-10, -10, -10, 10, 10, 10];
  for (let corner = 0; corner < 8; corner++) {
    const [sx, sy] = project(view, box[corner & 1 ? 3 : 0], box[corner & 2 ? 4 : 1], box[corner & 4 ? 5 : 2]);
    minX = Math.min(minX, sx); maxX = Math.max(maxX, sx);
    minY = Math.min(minY, sy); maxY = Math.max(maxY, sy);
  }
  const scale = 0.85 * Math.min(width / Math.max(maxX - minX, 1e-3), height / Math.max(maxY - minY, 1e-3));
  return { ...view, scale, x: -(minX + maxX) / 2, y: -(minY + maxY) / 2 };
}
