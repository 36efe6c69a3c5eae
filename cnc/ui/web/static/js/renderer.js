// The toolpath preview's drawing, done by the worker thread (program-worker.js) on an
// OffscreenCanvas, so that nothing the graphics card does can hold up the page's thread,
// which must answer STOP at once (a slow card makes the browser block the next call
// that draws or uploads until it has caught up; here that blocks only this worker).
//
// WebGL 2: the toolpath records (x, y, z float32 and line << 1 | kind,
// cnc/ui/web/preview.py) are uploaded as they arrive, as they are, and the card colours
// each segment by its kind and line (rapid, to cut, cut, selected) from a few numbers.
// The toolpath is drawn into an image of its own, again only when something in it
// changed; every frame lays that image under the tool's mark. While the view turns, or
// the toolpath still loads, a long one is drawn decimated (every k-th point); while a
// long program runs, the cut part is recoloured at most every RECOLOUR_MS. Without
// WebGL 2, a 2D canvas draws a decimated toolpath, at most twice a second.

import { rotation } from "./camera.js";

const RECORD = 16;
const DECIMATED_POINTS = 250_000;  // drawn while turning or loading, when longer
const UPLOAD_BYTES_PER_FRAME = 4 << 20;
const MAX_2D_SEGMENTS = 20_000;
const MIN_2D_REDRAW_MS = 500;
const BIG_PATH_POINTS = 50_000;  // longer toolpaths are recoloured at most every ...
const RECOLOUR_MS = 1000;
const TURNING_MS = 250;  // after the last turn of the view, the full toolpath again
const nextFrame = self.requestAnimationFrame ? (f) => self.requestAnimationFrame(f) : (f) => setTimeout(f, 16);

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
const IMAGE_VERTEX = `#version 300 es
out vec2 place;
void main() {  // one triangle covering the canvas
  vec2 corner = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
  place = corner;
  gl_Position = vec4(corner * 2.0 - 1.0, 0.0, 1.0);
}`;
const IMAGE_FRAGMENT = `#version 300 es
precision mediump float;
uniform sampler2D image;
in vec2 place;
out vec4 fragment;
void main() { fragment = texture(image, place); }`;

export class Renderer {
  // ``report(message)`` tells the page what is drawn: {points, drawn, renderer}.
  constructor(canvas, report) {
    this.canvas = canvas;
    this.report = report;
    this.width = 1; this.height = 1; this.ratio = 1;  // CSS pixels, device pixels per one
    this.view = null;
    this.colors = null;
    this.current = 0;
    this.selected = 0;
    this.tool = [0, 0, 0];
    this.limits = null;  // [[xmin, xmax], [ymin, ymax], [zmin, zmax]] in work coordinates
    this.isVisible = true;
    this.turnedAt = -Infinity;
    this.isDrawPending = false;
    // no antialiasing: a software card pays dearly for it
    this.gl = canvas.getContext("webgl2", { antialias: false });
    this.kind = this.gl ? "webgl" : "2d";
    if (this.gl) this.setUpGl();
    this.reset();
  }

  // ---------------------------------------------------------------- what to draw
  reset() {
    this.count = 0;  // records received
    this.uploaded = 0;  // ... and on the card
    this.pending = [];  // pieces waiting to be uploaded
    this.records = [];  // the 2D canvas keeps every piece
    this.decimated = null;
    this.redraw();
  }

  append(data) {
    this.count += data.byteLength / RECORD;
    this.pending.push(data);
    this.redraw();
  }

  set(changes) {  // any of width, height, ratio, view, colors, current, selected, tool,
    Object.assign(this, changes);  // limits, isVisible
    if ("turned" in changes) this.turnedAt = performance.now();
    const isOnlyTool = Object.keys(changes).every((key) => key === "tool");
    if (!isOnlyTool) this.isPathStale = true;
    this.draw();
  }

  redraw() {
    this.isPathStale = true;
    this.draw();
  }

  draw() {
    if (this.isDrawPending || !this.isVisible || !this.view || !this.colors) return;
    this.isDrawPending = true;
    const wait = this.gl ? 0 : Math.max(0, MIN_2D_REDRAW_MS - (performance.now() - (this.drawn2d || 0)));
    const paint = () => nextFrame(() => { this.isDrawPending = false; this.paint(); });
    if (wait) setTimeout(paint, wait); else paint();
  }

  paint() {
    const width = Math.max(1, Math.round(this.width * this.ratio));
    const height = Math.max(1, Math.round(this.height * this.ratio));
    if (this.canvas.width !== width || this.canvas.height !== height) {
      this.canvas.width = width;
      this.canvas.height = height;
      this.isPathStale = true;
    }
    if (this.gl) this.paintGl(); else this.paint2d();
    this.report({ points: this.count, drawn: this.drawn || 0, renderer: this.kind });
  }

  // ---------------------------------------------------------------- WebGL
  setUpGl() {
    const gl = this.gl;
    this.pathProgram = program(gl, PATH_VERTEX, PATH_FRAGMENT);
    this.plainProgram = program(gl, PLAIN_VERTEX, PLAIN_FRAGMENT);
    this.imageProgram = program(gl, IMAGE_VERTEX, IMAGE_FRAGMENT);
    this.pathVao = gl.createVertexArray();
    this.capacity = 0;
    this.buffer = null;
    this.indexBuffer = gl.createBuffer();
    this.image = { texture: gl.createTexture(), framebuffer: gl.createFramebuffer(), width: 0, height: 0 };
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

  // Upload pending pieces (at most UPLOAD_BYTES_PER_FRAME a frame); true if more wait.
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
    const [a, b] = rotation(this.view);
    const { scale, x, y } = this.view;
    const kx = (2 * scale) / this.width, ky = (2 * scale) / this.height;
    return new Float32Array([
      a[0] * kx, b[0] * ky, 0, 0,
      a[1] * kx, b[1] * ky, 0, 0,
      a[2] * kx, b[2] * ky, 0, 0,
      x * kx, y * ky, 0, 1,
    ]);
  }

  // The image the toolpath is drawn into, as big as the canvas.
  imageTarget() {
    const gl = this.gl, image = this.image;
    if (image.width !== this.canvas.width || image.height !== this.canvas.height) {
      image.width = this.canvas.width;
      image.height = this.canvas.height;
      gl.bindTexture(gl.TEXTURE_2D, image.texture);
      gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA8, image.width, image.height, 0, gl.RGBA, gl.UNSIGNED_BYTE, null);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
      gl.bindFramebuffer(gl.FRAMEBUFFER, image.framebuffer);
      gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, image.texture, 0);
      gl.bindFramebuffer(gl.FRAMEBUFFER, null);
      this.isPathStale = true;
    }
    return image;
  }

  paintGl() {
    const gl = this.gl, colors = this.colors;
    const transform = this.transform();
    const image = this.imageTarget();
    const now = performance.now();
    const isTurning = now - this.turnedAt < TURNING_MS;
    const isRecolourDue = this.count < BIG_PATH_POINTS || isTurning || now - (this.pathDrawnAt || 0) >= RECOLOUR_MS;
    let isMoreToDraw = false;
    if (this.pending.length || (this.isPathStale && isRecolourDue)) {
      const isUploading = this.upload();
      const isDecimated = (isTurning || isUploading) && this.uploaded > DECIMATED_POINTS;
      gl.bindFramebuffer(gl.FRAMEBUFFER, image.framebuffer);
      gl.viewport(0, 0, image.width, image.height);
      gl.clearColor(...colors.background);
      gl.clear(gl.COLOR_BUFFER_BIT);
      this.paintLimits(transform);
      this.paintPath(transform, isDecimated);
      gl.bindFramebuffer(gl.FRAMEBUFFER, null);
      this.isPathStale = isDecimated;  // the whole of it once the view rests
      this.pathDrawnAt = now;
      if (!isDecimated) this.drawn = this.uploaded;
      isMoreToDraw = isUploading || isDecimated;
    } else if (this.isPathStale) {
      isMoreToDraw = true;  // a recolouring, in a moment
    }
    gl.viewport(0, 0, this.canvas.width, this.canvas.height);
    gl.useProgram(this.imageProgram);
    gl.bindTexture(gl.TEXTURE_2D, image.texture);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
    this.paintTool(transform);
    if (isMoreToDraw) setTimeout(() => this.draw(), isTurning ? 16 : 100);
  }

  paintPath(transform, isDecimated) {
    const gl = this.gl, colors = this.colors;
    if (this.uploaded < 2) return;
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
    if (isDecimated) {
      const decimated = this.decimate();
      gl.drawElements(gl.LINE_STRIP, decimated.length, gl.UNSIGNED_INT, 0);
    } else {
      gl.drawArrays(gl.LINE_STRIP, 0, this.uploaded);
    }
    gl.bindVertexArray(null);
  }

  paintLimits(transform) {
    const box = this.limits;
    if (!box) return;
    this.plainLines(limitEdges(box), transform, this.colors.limits);
  }

  paintTool(transform) {
    this.plainLines(toolMark(this.tool, this.view.scale), transform, this.colors.tool);
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
    this.records.push(...this.pending.splice(0).map((data) => new DataView(data)));
    const g = this.canvas.getContext("2d");
    const colors = this.colors, ratio = this.ratio;
    const css = (c) => `rgba(${c[0] * 255},${c[1] * 255},${c[2] * 255},${c[3]})`;
    g.setTransform(1, 0, 0, 1, 0, 0);
    g.fillStyle = css(colors.background);
    g.fillRect(0, 0, this.canvas.width, this.canvas.height);
    g.setTransform(ratio, 0, 0, ratio, (this.width * ratio) / 2, (this.height * ratio) / 2);
    const [a, b] = rotation(this.view);
    const { scale, x: panX, y: panY } = this.view;
    const screen = (x, y, z) => [(a[0] * x + a[1] * y + a[2] * z + panX) * scale,
      -(b[0] * x + b[1] * y + b[2] * z + panY) * scale];
    const step = Math.max(1, Math.ceil(this.count / MAX_2D_SEGMENTS));
    const looks = [["rapid", (tag) => !(tag & 1)], ["feed", (tag) => (tag & 1) && (tag >> 1) >= this.current],
      ["done", (tag) => (tag & 1) && (tag >> 1) < this.current]];
    for (const [look, isWanted] of looks) {
      g.strokeStyle = css(colors[look]);
      g.lineWidth = 1;
      g.beginPath();
      let previous = null, index = 0;
      for (const view of this.records) {
        for (let offset = 0; offset < view.byteLength; offset += RECORD, index++) {
          if (index % step && offset + RECORD < view.byteLength) continue;
          const point = screen(view.getFloat32(offset, true), view.getFloat32(offset + 4, true),
            view.getFloat32(offset + 8, true));
          if (previous && isWanted(view.getUint32(offset + 12, true))) { g.moveTo(...previous); g.lineTo(...point); }
          previous = point;
        }
      }
      g.stroke();
    }
    const [tx, ty] = screen(...this.tool);
    g.strokeStyle = css(colors.tool);
    g.beginPath(); g.arc(tx, ty, 6, 0, 2 * Math.PI); g.stroke();
    this.drawn = this.count;
  }
}

// The 12 edges of the machine's limits, as line pairs.
function limitEdges(box) {
  const points = [];
  for (let edge = 0; edge < 12; edge++) {
    const axis = Math.floor(edge / 4), corner = edge % 4;
    const others = [0, 1, 2].filter((n) => n !== axis);
    const a = [0, 0, 0], b = [0, 0, 0];
    a[others[0]] = b[others[0]] = box[others[0]][corner & 1];
    a[others[1]] = b[others[1]] = box[others[1]][corner >> 1];
    a[axis] = box[axis][0]; b[axis] = box[axis][1];
    points.push(...a, ...b);
  }
  return points;
}

// A cross and a stem at the tool, 8 pixels wide whatever the zoom.
function toolMark([x, y, z], scale) {
  const size = 8 / scale;
  return [x - size, y, z, x + size, y, z, x, y - size, z, x, y + size, z, x, y, z, x, y, z + 3 * size];
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

