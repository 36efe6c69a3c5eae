// The toolpath preview, drawn by the graphics card (WebGL 2). The toolpath records
// (x, y, z float32 and line << 1 | kind, cnc/ui/web/preview.py) are uploaded as they
// arrive, as they are: the card colours each segment by its kind and line (rapid, to cut,
// cut, selected) from a few numbers given per frame, so following a running program
// costs the page's thread almost nothing. Long toolpaths load in pieces (drawn as they
// come) and, while the view is being turned, are drawn decimated (every k-th point).
// Without WebGL 2 a 2D canvas draws a decimated toolpath, a few times a second at most.
//
// Orthographic views: drag turns, shift+drag or two fingers pan, the wheel zooms.

const RECORD = 16;
const DECIMATED_POINTS = 250_000;  // drawn while turning, when the toolpath is longer
const UPLOAD_BYTES_PER_FRAME = 1 << 20;
const MAX_2D_SEGMENTS = 60_000;
const MIN_2D_REDRAW_MS = 250;
const INTERACTION_MS = 250;  // after the last drag or wheel, the full toolpath again
// [yaw about Z, pitch about the screen's x, roll in the screen plane]
export const CAMERAS = {
  top: [0, 0, 0], front: [0, -Math.PI / 2, 0], side: [-Math.PI / 2, -Math.PI / 2, 0],
  iso: [-Math.PI / 4, -0.96, 0], lathe: [Math.PI, -Math.PI / 2, -Math.PI / 2],
};

const PATH_VERTEX = `#version 300 es
layout(location = 0) in vec3 position;
layout(location = 1) in uint tag;
uniform mat4 transform;
uniform float current;   // the line being cut (0: not running)
uniform float selected;  // the line chosen in the listing (0: none)
uniform vec4 rapidColor, feedColor, doneColor, selectedColor;
flat out vec4 color;
void main() {
  gl_Position = transform * vec4(position, 1.0);
  float line = float(tag >> 1u);
  bool isRapid = (tag & 1u) == 0u;
  if (line == selected && selected > 0.0) color = selectedColor;
  else if (isRapid) color = rapidColor;
  else if (line < current) color = doneColor;
  else color = feedColor;
}`;
const PATH_FRAGMENT = `#version 300 es
precision mediump float;
flat in vec4 color;
out vec4 fragment;
void main() { fragment = color; }`;
const PLAIN_VERTEX = `#version 300 es
layout(location = 0) in vec3 position;
uniform mat4 transform;
void main() { gl_Position = transform * vec4(position, 1.0); }`;
const PLAIN_FRAGMENT = `#version 300 es
precision mediump float;
uniform vec4 color;
out vec4 fragment;
void main() { fragment = color; }`;

export class Preview {
  constructor(canvas) {
    this.canvas = canvas;
    this.view = { yaw: CAMERAS.iso[0], pitch: CAMERAS.iso[1], roll: 0, scale: 1, x: 0, y: 0 };
    this.count = 0;  // records received
    this.bounds = null;
    this.current = 0;
    this.selected = 0;
    this.tool = [0, 0, 0];
    this.limits = null;  // [[xmin, xmax], [ymin, ymax], [zmin, zmax]] in work coordinates
    this.pending = [];  // chunks waiting to be uploaded
    this.lastInteraction = 0;
    this.isMovedByOperator = false;  // turned, panned or zoomed since the toolpath came
    this.isVisible = true;
    this.isDrawPending = false;
    this.gl = canvas.getContext("webgl2", { antialias: true });
    if (this.gl) this.setUpGl();
    else this.records = new Uint8Array(0);  // the 2D canvas keeps them itself
    this.kind = this.gl ? "webgl" : "2d";
    canvas.dataset.renderer = this.kind;
    this.listenToPointers();
    new ResizeObserver(() => this.draw()).observe(canvas);
  }

  // ---------------------------------------------------------------- data
  reset() {
    this.isMovedByOperator = false;
    this.count = 0;
    this.uploaded = 0;
    this.bounds = null;
    this.pending = [];
    this.decimated = null;
    if (!this.gl) this.records = new Uint8Array(0);
    this.canvas.dataset.points = 0;
    this.draw();
  }

  append(first, data, bounds) {
    if (first !== this.count) return;  // out of order: a stale piece
    this.count += data.byteLength / RECORD;
    this.bounds = bounds;
    this.pending.push(data);
    this.canvas.dataset.points = this.count;
    this.draw();
  }

  setLines(current, selected) {
    if (current === this.current && selected === this.selected) return;
    this.current = current;
    this.selected = selected;
    this.draw();
  }

  setTool(position, limits) {
    this.tool = position;
    this.limits = limits;
    this.draw();
  }

  setCamera(name) {
    const camera = CAMERAS[name];
    if (camera) [this.view.yaw, this.view.pitch, this.view.roll] = camera;
    this.fit();
  }

  fit() {
    const view = this.view;
    let [minX, minY, maxX, maxY] = [Infinity, Infinity, -Infinity, -Infinity];
    const box = this.bounds ? this.bounds : [-10, -10, -10, 10, 10, 10];
    for (let corner = 0; corner < 8; corner++) {
      const [sx, sy] = this.project(box[corner & 1 ? 3 : 0], box[corner & 2 ? 4 : 1], box[corner & 4 ? 5 : 2]);
      minX = Math.min(minX, sx); maxX = Math.max(maxX, sx);
      minY = Math.min(minY, sy); maxY = Math.max(maxY, sy);
    }
    const width = this.canvas.clientWidth || 400, height = this.canvas.clientHeight || 300;
    view.scale = 0.85 * Math.min(width / Math.max(maxX - minX, 1e-3), height / Math.max(maxY - minY, 1e-3));
    view.x = -(minX + maxX) / 2;
    view.y = -(minY + maxY) / 2;
    this.draw();
  }

  // The screen coordinates (before pan and zoom) of a point, and their matrix.
  rotation() {
    const { yaw, pitch, roll } = this.view;
    const cy = Math.cos(yaw), sy = Math.sin(yaw), cp = Math.cos(pitch), sp = Math.sin(pitch);
    const cr = Math.cos(roll), sr = Math.sin(roll);
    return [
      [cr * cy - sr * cp * sy, -cr * sy - sr * cp * cy, sr * sp],
      [sr * cy + cr * cp * sy, -sr * sy + cr * cp * cy, -cr * sp],
    ];
  }

  project(x, y, z) {
    const [a, b] = this.rotation();
    return [a[0] * x + a[1] * y + a[2] * z, b[0] * x + b[1] * y + b[2] * z];
  }

  // ---------------------------------------------------------------- drawing
  draw() {
    if (this.isDrawPending || !this.isVisible) return;
    this.isDrawPending = true;
    const wait = this.gl ? 0 : Math.max(0, MIN_2D_REDRAW_MS - (performance.now() - (this.drawn2d || 0)));
    const paint = () => requestAnimationFrame(() => { this.isDrawPending = false; this.paint(); });
    if (wait) setTimeout(paint, wait); else paint();
  }

  resize() {
    const ratio = window.devicePixelRatio || 1;
    const width = Math.round(this.canvas.clientWidth * ratio), height = Math.round(this.canvas.clientHeight * ratio);
    if (this.canvas.width !== width || this.canvas.height !== height) {
      this.canvas.width = width;
      this.canvas.height = height;
    }
    return ratio;
  }

  paint() {
    if (!this.canvas.clientWidth) return;  // hidden
    if (this.gl) this.paintGl(); else this.paint2d();
  }

  colors() {
    const style = getComputedStyle(this.canvas);
    const read = (name) => cssColor(style.getPropertyValue(name));
    return {
      background: read("--preview-bg"), rapid: read("--path-rapid"), feed: read("--path-feed"),
      done: read("--path-done"), selected: read("--path-selected"), limits: read("--path-limits"),
      tool: read("--path-tool"),
    };
  }

  // ---------------------------------------------------------------- WebGL
  setUpGl() {
    const gl = this.gl;
    this.pathProgram = program(gl, PATH_VERTEX, PATH_FRAGMENT);
    this.plainProgram = program(gl, PLAIN_VERTEX, PLAIN_FRAGMENT);
    this.pathVao = gl.createVertexArray();
    this.capacity = 0;
    this.buffer = null;
    this.uploaded = 0;
    this.indexBuffer = gl.createBuffer();
    this.decimated = null;  // {count (records it covers), length (indexes)}
    this.plainVao = gl.createVertexArray();
    this.plainBuffer = gl.createBuffer();
    gl.bindVertexArray(this.plainVao);
    gl.bindBuffer(gl.ARRAY_BUFFER, this.plainBuffer);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 12, 0);
    gl.bindVertexArray(null);
  }

  // Make room for ``records`` on the card, keeping what is there (a copy on the card).
  reserve(records) {
    const gl = this.gl;
    if (records <= this.capacity) return;
    const capacity = Math.max(records, this.capacity * 2, 65_536);
    const buffer = gl.createBuffer();
    gl.bindBuffer(gl.COPY_WRITE_BUFFER, buffer);
    gl.bufferData(gl.COPY_WRITE_BUFFER, capacity * RECORD, gl.STATIC_DRAW);
    if (this.buffer && this.uploaded) {
      gl.bindBuffer(gl.COPY_READ_BUFFER, this.buffer);
      gl.copyBufferSubData(gl.COPY_READ_BUFFER, gl.COPY_WRITE_BUFFER, 0, 0, this.uploaded * RECORD);
    }
    if (this.buffer) gl.deleteBuffer(this.buffer);
    this.buffer = buffer;
    this.capacity = capacity;
    gl.bindVertexArray(this.pathVao);
    gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribPointer(0, 3, gl.FLOAT, false, RECORD, 0);
    gl.enableVertexAttribArray(1);
    gl.vertexAttribIPointer(1, 1, gl.UNSIGNED_INT, RECORD, 12);
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.indexBuffer);
    gl.bindVertexArray(null);
  }

  // Upload a few pending pieces (at most UPLOAD_BYTES_PER_FRAME a frame); true if more wait.
  upload() {
    const gl = this.gl;
    let budget = UPLOAD_BYTES_PER_FRAME;
    while (this.pending.length && budget > 0) {
      const data = this.pending.shift();
      const records = data.byteLength / RECORD;
      this.reserve(this.uploaded + records);
      gl.bindBuffer(gl.ARRAY_BUFFER, this.buffer);
      gl.bufferSubData(gl.ARRAY_BUFFER, this.uploaded * RECORD, new Uint8Array(data));
      this.uploaded += records;
      budget -= data.byteLength;
    }
    return this.pending.length > 0;
  }

  // Every k-th point of the toolpath (and the last), for drawing while the view turns.
  decimate() {
    const gl = this.gl;
    if (this.decimated && this.decimated.count === this.uploaded) return this.decimated;
    const step = Math.ceil(this.uploaded / DECIMATED_POINTS);
    const indexes = new Uint32Array(Math.ceil(this.uploaded / step) + 1);
    let length = 0;
    for (let i = 0; i < this.uploaded; i += step) indexes[length++] = i;
    if (indexes[length - 1] !== this.uploaded - 1) indexes[length++] = this.uploaded - 1;
    gl.bindVertexArray(this.pathVao);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, indexes.subarray(0, length), gl.STATIC_DRAW);
    gl.bindVertexArray(null);
    this.decimated = { count: this.uploaded, length };
    return this.decimated;
  }

  transform() {
    const [a, b] = this.rotation();
    const { scale, x, y } = this.view;
    const kx = (2 * scale) / (this.canvas.clientWidth || 1), ky = (2 * scale) / (this.canvas.clientHeight || 1);
    return new Float32Array([
      a[0] * kx, b[0] * ky, 0, 0,
      a[1] * kx, b[1] * ky, 0, 0,
      a[2] * kx, b[2] * ky, 0, 0,
      x * kx, y * ky, 0, 1,
    ]);
  }

  paintGl() {
    const gl = this.gl;
    this.resize();
    const isUploading = this.upload();
    const colors = this.colors();
    gl.viewport(0, 0, this.canvas.width, this.canvas.height);
    gl.clearColor(...colors.background);
    gl.clear(gl.COLOR_BUFFER_BIT);
    const transform = this.transform();
    this.paintOverlay(transform, colors);
    if (this.uploaded > 1) {
      gl.useProgram(this.pathProgram);
      const uniform = (name) => gl.getUniformLocation(this.pathProgram, name);
      gl.uniformMatrix4fv(uniform("transform"), false, transform);
      gl.uniform1f(uniform("current"), this.current);
      gl.uniform1f(uniform("selected"), this.selected);
      gl.uniform4fv(uniform("rapidColor"), colors.rapid);
      gl.uniform4fv(uniform("feedColor"), colors.feed);
      gl.uniform4fv(uniform("doneColor"), colors.done);
      gl.uniform4fv(uniform("selectedColor"), colors.selected);
      gl.bindVertexArray(this.pathVao);
      const isTurning = performance.now() - this.lastInteraction < INTERACTION_MS;
      if ((isTurning || isUploading) && this.uploaded > DECIMATED_POINTS) {
        const decimated = this.decimate();
        gl.drawElements(gl.LINE_STRIP, decimated.length, gl.UNSIGNED_INT, 0);
        setTimeout(() => this.draw(), INTERACTION_MS);  // then the whole of it
      } else {
        gl.drawArrays(gl.LINE_STRIP, 0, this.uploaded);
      }
      gl.bindVertexArray(null);
    }
    this.paintTool(transform, colors);
    this.canvas.dataset.drawn = this.uploaded;
    if (isUploading) this.draw();
  }

  paintOverlay(transform, colors) {
    const box = this.limits;
    if (!box) return;
    const points = [];
    for (let edge = 0; edge < 12; edge++) {  // the 12 edges of the machine's limits
      const axis = Math.floor(edge / 4), corner = edge % 4;
      const others = [0, 1, 2].filter((n) => n !== axis);
      const a = [0, 0, 0], b = [0, 0, 0];
      a[others[0]] = b[others[0]] = box[others[0]][corner & 1];
      a[others[1]] = b[others[1]] = box[others[1]][corner >> 1];
      a[axis] = box[axis][0]; b[axis] = box[axis][1];
      points.push(...a, ...b);
    }
    this.plainLines(points, transform, colors.limits);
  }

  paintTool(transform, colors) {
    const [x, y, z] = this.tool;
    const size = 8 / this.view.scale;  // 8 pixels
    this.plainLines([x - size, y, z, x + size, y, z, x, y - size, z, x, y + size, z,
      x, y, z, x, y, z + 3 * size], transform, colors.tool);
  }

  plainLines(points, transform, color) {
    const gl = this.gl;
    gl.useProgram(this.plainProgram);
    gl.uniformMatrix4fv(gl.getUniformLocation(this.plainProgram, "transform"), false, transform);
    gl.uniform4fv(gl.getUniformLocation(this.plainProgram, "color"), color);
    gl.bindVertexArray(this.plainVao);
    gl.bindBuffer(gl.ARRAY_BUFFER, this.plainBuffer);
    gl.bufferData(gl.ARRAY_BUFFER, new Float32Array(points), gl.DYNAMIC_DRAW);
    gl.drawArrays(gl.LINES, 0, points.length / 3);
    gl.bindVertexArray(null);
  }

  // ---------------------------------------------------------------- 2D canvas
  paint2d() {
    this.drawn2d = performance.now();
    for (const data of this.pending.splice(0)) {  // kept here: no card to keep them
      const joined = new Uint8Array(this.records.length + data.byteLength);
      joined.set(this.records); joined.set(new Uint8Array(data), this.records.length);
      this.records = joined;
    }
    const ratio = this.resize();
    const g = this.canvas.getContext("2d");
    const colors = this.colors();
    const css = (c) => `rgba(${c[0] * 255},${c[1] * 255},${c[2] * 255},${c[3]})`;
    g.setTransform(1, 0, 0, 1, 0, 0);
    g.fillStyle = css(colors.background);
    g.fillRect(0, 0, this.canvas.width, this.canvas.height);
    g.setTransform(ratio, 0, 0, ratio, this.canvas.clientWidth * ratio / 2, this.canvas.clientHeight * ratio / 2);
    const [a, b] = this.rotation();
    const { scale, x: panX, y: panY } = this.view;
    const view = new DataView(this.records.buffer);
    const count = this.records.length / RECORD;
    const step = Math.max(1, Math.ceil(count / MAX_2D_SEGMENTS));
    const screen = (i) => {
      const x = view.getFloat32(i * RECORD, true), y = view.getFloat32(i * RECORD + 4, true);
      const z = view.getFloat32(i * RECORD + 8, true);
      return [(a[0] * x + a[1] * y + a[2] * z + panX) * scale, -(b[0] * x + b[1] * y + b[2] * z + panY) * scale];
    };
    const looks = [["rapid", (tag) => !(tag & 1)], ["feed", (tag) => (tag & 1) && (tag >> 1) >= this.current],
      ["done", (tag) => (tag & 1) && (tag >> 1) < this.current]];
    for (const [look, wanted] of looks) {
      g.strokeStyle = css(colors[look]);
      g.lineWidth = 1;
      g.beginPath();
      let previous = count ? screen(0) : null;
      for (let i = step; i < count; i += step) {
        const point = screen(i);
        if (wanted(view.getUint32(i * RECORD + 12, true))) { g.moveTo(...previous); g.lineTo(...point); }
        previous = point;
      }
      g.stroke();
    }
    const [tx, ty] = (() => {
      const [x, y, z] = this.tool;
      return [(a[0] * x + a[1] * y + a[2] * z + panX) * scale, -(b[0] * x + b[1] * y + b[2] * z + panY) * scale];
    })();
    g.strokeStyle = css(colors.tool);
    g.beginPath(); g.arc(tx, ty, 6, 0, 2 * Math.PI); g.stroke();
    this.canvas.dataset.drawn = count;
  }

  // ---------------------------------------------------------------- pointers
  listenToPointers() {
    const canvas = this.canvas, view = this.view;
    const pointers = new Map();
    canvas.addEventListener("pointerdown", (event) => {
      canvas.setPointerCapture(event.pointerId);
      pointers.set(event.pointerId, [event.clientX, event.clientY]);
    });
    canvas.addEventListener("pointermove", (event) => {
      const last = pointers.get(event.pointerId);
      if (!last) return;
      const dx = event.clientX - last[0], dy = event.clientY - last[1];
      pointers.set(event.pointerId, [event.clientX, event.clientY]);
      if (event.shiftKey || pointers.size > 1) {
        view.x += dx / view.scale / pointers.size;
        view.y -= dy / view.scale / pointers.size;
      } else {
        view.yaw += dx * 0.01;
        view.pitch = Math.max(-Math.PI, Math.min(0, view.pitch + dy * 0.01));
      }
      this.lastInteraction = performance.now();
      this.isMovedByOperator = true;
      this.draw();
    });
    const release = (event) => pointers.delete(event.pointerId);
    canvas.addEventListener("pointerup", release);
    canvas.addEventListener("pointercancel", release);
    canvas.addEventListener("wheel", (event) => {
      event.preventDefault();
      view.scale *= event.deltaY < 0 ? 1.15 : 1 / 1.15;
      this.lastInteraction = performance.now();
      this.isMovedByOperator = true;
      this.draw();
    }, { passive: false });
  }
}

function program(gl, vertexSource, fragmentSource) {
  const compile = (kind, source) => {
    const shader = gl.createShader(kind);
    gl.shaderSource(shader, source);
    gl.compileShader(shader);
    if (!gl.getShaderParameter(shader, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(shader));
    return shader;
  };
  const linked = gl.createProgram();
  gl.attachShader(linked, compile(gl.VERTEX_SHADER, vertexSource));
  gl.attachShader(linked, compile(gl.FRAGMENT_SHADER, fragmentSource));
  gl.linkProgram(linked);
  if (!gl.getProgramParameter(linked, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(linked));
  return linked;
}

// "#rrggbb" or "rgb(r, g, b)" -> [r, g, b, 1] in 0..1
function cssColor(text) {
  const value = text.trim();
  if (value.startsWith("#")) {
    const hex = value.length === 4 ? [...value.slice(1)].map((c) => c + c).join("") : value.slice(1, 7);
    return [0, 2, 4].map((i) => parseInt(hex.slice(i, i + 2), 16) / 255).concat(1);
  }
  const numbers = value.match(/[\d.]+/g) || ["0", "0", "0"];
  return [Number(numbers[0]) / 255, Number(numbers[1]) / 255, Number(numbers[2]) / 255, numbers[3] ? Number(numbers[3]) : 1];
}
