// A toolpath's level of detail: the few points that keep its shape, drawn instead of the
// whole toolpath while the operator turns, pans or zooms the view of a long program.
//
// Douglas-Peucker in 3D: of a run of points, the ends are kept, and the point farthest
// from the segment between them splits the run in two, as long as it lies farther than
// the tolerance; every point dropped is within the tolerance of the line drawn. Runs are
// cut where rapids and feeds meet (both kinds keep their exact ends) and at WINDOW points
// (the work stays linear in the toolpath's length whatever its shape). Records as
// cnc/ui/web/preview.py writes them: x, y, z float32 and line << 1 | kind, 16 bytes.

const RECORD = 16;
const WINDOW = 4096;  // points per run at most

export class Decimator {
  // Points are given in pieces (``add``); ``records`` holds what is kept, ``count`` of them.
  constructor(tolerance) {
    this.tolerance = tolerance;
    this.setRecords(new ArrayBuffer(RECORD * 1024));
    this.count = 0;
    // the run being gathered: its first point is the last one kept
    this.xyz = new Float32Array(3 * (WINDOW + 1));
    this.tags = new Uint32Array(WINDOW + 1);
    this.length = 0;
    this.keep = new Uint8Array(WINDOW + 1);
    this.stack = new Int32Array(2 * (WINDOW + 1));
  }

  // A piece of toolpath (an ArrayBuffer of records), continuing the ones before.
  add(data) {
    const floats = new Float32Array(data), tags = new Uint32Array(data);
    const records = data.byteLength / RECORD;
    for (let i = 0; i < records; i++) {
      const tag = tags[i * 4 + 3];
      if (this.count === 0 && this.length === 0) {  // the very first point: kept
        this.emit(floats[i * 4], floats[i * 4 + 1], floats[i * 4 + 2], tag);
        this.startRun();
        continue;
      }
      const isOtherKind = this.length > 1 && ((this.tags[1] ^ tag) & 1) === 1;
      if (isOtherKind || this.length === WINDOW + 1) this.endRun();
      const at = this.length++;
      this.xyz[3 * at] = floats[i * 4];
      this.xyz[3 * at + 1] = floats[i * 4 + 1];
      this.xyz[3 * at + 2] = floats[i * 4 + 2];
      this.tags[at] = tag;
    }
    if (this.length > 1) this.endRun();  // everything given so far is in ``records``
  }

  setRecords(buffer) {
    this.records = buffer;
    this.floats = new Float32Array(buffer);
    this.words = new Uint32Array(buffer);
  }

  // The last kept point starts the next run.
  startRun() {
    const at = 4 * (this.count - 1);
    this.xyz[0] = this.floats[at]; this.xyz[1] = this.floats[at + 1]; this.xyz[2] = this.floats[at + 2];
    this.tags[0] = this.words[at + 3];
    this.length = 1;
  }

  endRun() {
    const { xyz, keep, stack } = this;
    const last = this.length - 1;
    keep.fill(0, 0, this.length);
    keep[last] = 1;
    let top = 0;
    stack[top++] = 0; stack[top++] = last;
    const limit = this.tolerance * this.tolerance;
    while (top > 0) {
      const end = stack[--top], start = stack[--top];
      if (end - start < 2) continue;
      let farthest = -1, distance = limit;
      for (let i = start + 1; i < end; i++) {
        const d = squaredDistance(xyz, i, start, end);
        if (d > distance) { distance = d; farthest = i; }
      }
      if (farthest < 0) continue;
      keep[farthest] = 1;
      stack[top++] = start; stack[top++] = farthest;
      stack[top++] = farthest; stack[top++] = end;
    }
    for (let i = 1; i <= last; i++) {
      if (keep[i]) this.emit(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2], this.tags[i]);
    }
    this.startRun();
  }

  emit(x, y, z, tag) {
    if ((this.count + 1) * RECORD > this.records.byteLength) {
      const bigger = new ArrayBuffer(this.records.byteLength * 2);
      new Uint8Array(bigger).set(new Uint8Array(this.records));
      this.setRecords(bigger);
    }
    const at = 4 * this.count++;
    this.floats[at] = x; this.floats[at + 1] = y; this.floats[at + 2] = z;
    this.words[at + 3] = tag;
  }

  // The kept records (a view, valid until the next ``add``).
  kept() { return new Uint8Array(this.records, 0, this.count * RECORD); }
}

// A level of detail of ``pieces`` (ArrayBuffers of records) with at most ``maxPoints``
// points: the tolerance doubled from ``tolerance`` until they fit.
export function levelWithin(pieces, tolerance, maxPoints) {
  for (let level = new Decimator(tolerance); ; level = new Decimator(level.tolerance * 2)) {
    for (const piece of pieces) level.add(piece);
    if (level.count <= maxPoints) return level;
  }
}

// The squared distance of point i from the segment between points a and b.
function squaredDistance(xyz, i, a, b) {
  const ax = xyz[3 * a], ay = xyz[3 * a + 1], az = xyz[3 * a + 2];
  const dx = xyz[3 * b] - ax, dy = xyz[3 * b + 1] - ay, dz = xyz[3 * b + 2] - az;
  const px = xyz[3 * i] - ax, py = xyz[3 * i + 1] - ay, pz = xyz[3 * i + 2] - az;
  const length = dx * dx + dy * dy + dz * dz;
  let t = length > 0 ? (px * dx + py * dy + pz * dz) / length : 0;
  t = t < 0 ? 0 : t > 1 ? 1 : t;
  const ex = px - t * dx, ey = py - t * dy, ez = pz - t * dz;
  return ex * ex + ey * ey + ez * ez;
}
