// The toolpath preview's drawing, done by the worker thread (program-worker.js) on an
// OffscreenCanvas, so that nothing the graphics card does can hold up the page's thread,
// which must answer STOP at once (a slow card makes the browser block the next call
// that draws or uploads until it has caught up; here that blocks only this worker).
//
// WebGL 2: the toolpath records (x, y, z float32 and line << 1 | kind,
// cnc/ui/web/preview.py) are uploaded once, as they arrive, as they are, and the card
// colours each segment by its kind and line (rapid, to cut, cut, selected) from a few
// numbers. The toolpath is drawn into an image of its own, which every frame lays under
// the tool's mark; nothing per frame costs the page's or this thread time in proportion
// to the toolpath's length. What arrives while the program loads is drawn on top of what
// is there. A long toolpath (over FULL_POINTS_PER_FRAME) costs more than one frame to
// draw whole: a change of the view (turn, pan, zoom, size, colours) draws its level of
// detail (lod.js: the points that keep its shape, made once as it arrives, in a buffer
// of its own) at once (while the view turns, at a lower resolution, and on a card too
// slow for it, TurnPace, a coarser level of its own), and, once the view rests for
// TURNING_MS, the whole toolpath is drawn into a second image, FULL_POINTS_PER_FRAME
// points a frame, which then takes the first one's place. While a long program runs, the
// cut part is recoloured that way too, at most every RECOLOUR_MS. Without WebGL 2, a 2D
// canvas draws a decimated toolpath, at most twice a second.

import { rotation } from "./camera.js";
import { Decimator, levelWithin } from "./lod.js";

const RECORD = 16;
// the whole toolpath is drawn this many points a frame (a software renderer takes about
// 2.3 us of CPU a segment, shared by its threads: a 1M-line program comes back in 10 frames)
const FULL_POINTS_PER_FRAME = 100_000;
const LOD_TOLERANCE = 1 / 1500;  // of the toolpath's diagonal: about a pixel when fitted
const LOD_MAX_POINTS = 120_000;  // over this, a coarser level of detail
const UPLOAD_BYTES_PER_FRAME = 8 << 20;
const MAX_2D_SEGMENTS = 20_000;
const MIN_2D_REDRAW_MS = 500;
const BIG_PATH_POINTS = 50_000;  // longer toolpaths are recoloured at most every ...
const RECOLOUR_MS = 1000;
const TURNING_MS = 250;  // after the last turn of the view, the whole toolpath again
// ... or this long while the hand still holds it: on a slow card a drag's moves come
// further apart than TURNING_MS, and drawing the whole toolpath between them (a frame's
// part of it, then from the start after the next move) slowed the turn further
const HELD_TURNING_MS = 1000;
// while the view turns, a long toolpath's level of detail is drawn at 1/TURNING_SCALE of the
// canvas's size, then shown stretched: fewer pixels to fill and to show
const TURNING_SCALE = 2;
// a card that draws the level of detail slower than this while the view turns gets a
// coarser one, of TURNING_MAX_POINTS (software: about 2.3 us of CPU a segment, 2 cores)
const SLOW_TURN_FRAME_MS = 50;
const TURNING_MAX_POINTS = 16_000;
const PACE_SAMPLES = 4;
const VIEW_KEYS = ["width", "height", "ratio", "view", "colors", "limits"];
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
  // ``report(message)`` tells the page what is drawn: {points, drawn, renderer, frames, lod,
  // turningLod}.
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
    this.isHeld = false;  // the operator's hand holds the view (a button down on it)
    this.isDrawPending = false;
    this.frames = 0;  // frames shown (ui_bench counts them while the view turns)
    this.turningLod = 0;  // points of the level last drawn while the view turned
    // no antialiasing: a software card pays dearly for it
    this.gl = canvas.getContext("webgl2", { antialias: false });
    this.kind = this.gl ? "webgl" : "2d";
    this.pace = new TurnPace(Boolean(this.gl) && isSoftwareCard(this.gl));
    if (this.gl) this.setUpGl();
    this.reset();
  }

  // ---------------------------------------------------------------- what to draw
  reset() {
    this.count = 0;  // records received
    this.uploaded = 0;  // ... and on the card
    this.pending = [];  // pieces waiting to be uploaded
    this.pieces = [];  // every piece (the level of detail is made again from them)
    this.bounds = null;
    this.lod = null;  // a Decimator
    this.lodUploaded = -1;  // records of the level of detail on the card
    this.coarseFrom = -1;  // ... of which the coarse level on the card was made
    this.coarseUploaded = 0;  // records of the coarse level on the card
    this.drawn = 0;
    this.frontPoints = 0;  // toolpath points in the image shown; null: its level of detail
    this.refining = null;  // the whole toolpath being drawn into the second image
    this.isLodGrown = false;
    this.isViewStale = true;  // the image shown is not of the view
    this.isLinesStale = false;  // ... nor of the current and selected lines
    this.draw();
  }

  // A piece of toolpath (records); ``bounds``: of the whole toolpath so far.
  append(data, bounds) {
    this.count += data.byteLength / RECORD;
    this.pending.push(data);
    this.pieces.push(data);
    this.bounds = bounds;
    if (this.gl) this.growLod(data);
    this.draw();
  }

  set(changes) {  // any of width, height, ratio, view, colors, current, selected, tool,
    // limits, isVisible, turned, isHeld
    if ("limits" in changes && JSON.stringify(changes.limits) === JSON.stringify(this.limits)) {
      delete changes.limits;  // sent with every move of the tool
    }
    if (VIEW_KEYS.some((key) => key in changes) || (changes.isVisible && !this.isVisible)) {
      this.isViewStale = true;
    }
    if (("current" in changes && changes.current !== this.current)
        || ("selected" in changes && changes.selected !== this.selected)) {
      this.isLinesStale = true;
    }
    if (changes.turned) this.turnedAt = performance.now();
    delete changes.turned;
    Object.assign(this, changes);
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
      this.isViewStale = true;
    }
    if (this.gl) this.paintGl(); else this.paint2d();
    this.frames++;
    this.report({ points: this.count, drawn: this.drawn, renderer: this.kind, frames: this.frames,
      lod: this.lod ? this.lod.count : 0, turningLod: this.turningLod });
  }

  // ---------------------------------------------------------------- level of detail
  growLod(data) {
    const tolerance = LOD_TOLERANCE * diagonal(this.bounds);
    if (!this.lod) this.lod = new Decimator(tolerance);
    this.lod.add(data);
    while (this.lod.count > LOD_MAX_POINTS) {  // coarser, from the start
      this.lod = new Decimator(this.lod.tolerance * 2);
      for (const piece of this.pieces) this.lod.add(piece);
    }
    this.lodUploaded = -1;
  }

  // ---------------------------------------------------------------- WebGL
  setUpGl() {
    const gl = this.gl;
    this.pathProgram = program(gl, PATH_VERTEX, PATH_FRAGMENT);
    this.plainProgram = program(gl, PLAIN_VERTEX, PLAIN_FRAGMENT);
    this.imageProgram = program(gl, IMAGE_VERTEX, IMAGE_FRAGMENT);
    this.uniforms = {};
    for (const name of ["transform", "current", "selected", "rapidColor", "feedColor", "doneColor", "selectedColor"]) {
      this.uniforms[name] = gl.getUniformLocation(this.pathProgram, name);
    }
    this.pathVao = gl.createVertexArray();
    this.capacity = 0;
    this.buffer = null;
    this.lodVao = gl.createVertexArray();
    this.lodBuffer = gl.createBuffer();
    bindRecords(gl, this.lodVao, this.lodBuffer);
    this.coarseVao = gl.createVertexArray();
    this.coarseBuffer = gl.createBuffer();
    bindRecords(gl, this.coarseVao, this.coarseBuffer);
    this.front = newImage(gl);  // shown
    this.back = newImage(gl);  // the whole toolpath drawn into it, a part a frame
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
    bindRecords(gl, this.pathVao, buffer);
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
    if (this.lod && this.lodUploaded !== this.lod.count) {
      gl.bindBuffer(gl.ARRAY_BUFFER, this.lodBuffer);
      gl.bufferData(gl.ARRAY_BUFFER, this.lod.kept(), gl.STATIC_DRAW);
      this.lodUploaded = this.lod.count;
      this.isLodGrown = true;
    }
    return this.pending.length > 0;
  }

  // The level of detail drawn while the view turns: [vao, points]; on a slow card, a
  // coarser one than the rest of the time, made from it when first needed.
  turningLevel() {
    if (!this.pace.isSlow || this.lodUploaded <= TURNING_MAX_POINTS) {
      return [this.lodVao, this.lodUploaded];
    }
    if (this.coarseFrom !== this.lodUploaded) {
      const gl = this.gl;
      const coarse = levelWithin([this.lod.kept().slice().buffer], this.lod.tolerance * 2,
        TURNING_MAX_POINTS);
      gl.bindBuffer(gl.ARRAY_BUFFER, this.coarseBuffer);
      gl.bufferData(gl.ARRAY_BUFFER, coarse.kept(), gl.STATIC_DRAW);
      this.coarseFrom = this.lodUploaded;
      this.coarseUploaded = coarse.count;
    }
    return [this.coarseVao, this.coarseUploaded];
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

  // What the toolpath is drawn with: the view and the lines of this moment.
  look() {
    return { transform: this.transform(), current: this.current, selected: this.selected };
  }

  // Each frame: the toolpath image brought up to date (within a frame's work), then shown
  // under the tool's mark.
  paintGl() {
    const gl = this.gl;
    const now = performance.now();
    const isTurning = now - this.turnedAt < (this.isHeld ? HELD_TURNING_MS : TURNING_MS);
    const isUploading = this.upload();
    const isLong = this.uploaded > FULL_POINTS_PER_FRAME && this.lodUploaded > 1;
    const isRecolourDue = this.count < BIG_PATH_POINTS || now - (this.recolouredAt || 0) >= RECOLOUR_MS;
    if (this.isViewStale || (this.isLinesStale && isRecolourDue && !isLong)) {
      const look = this.look();
      if (isLong) {
        if (isTurning) {
          this.pace.frame(now);
          this.paintLod(look, TURNING_SCALE, ...this.turningLevel());
        } else {
          this.paintLod(look);
        }
        this.refining = { look, points: 0 };  // the whole of it, when the view rests
      } else {
        this.clearImage(this.front, look);
        this.paintMore(this.front, 0, look);
        this.frontPoints = Math.min(this.uploaded, FULL_POINTS_PER_FRAME);
        this.refining = null;
      }
      this.isViewStale = this.isLinesStale = false;
      this.recolouredAt = now;
    } else if (this.isLinesStale && isRecolourDue && !this.refining) {
      this.refining = { look: this.look(), points: 0 };  // shown when whole
      this.isLinesStale = false;
      this.recolouredAt = now;
    } else if (this.frontPoints === null && this.isLodGrown) {
      this.paintLod(this.look());  // the program still loads
    }
    if (this.refining && !isTurning) {
      this.refine();
    } else if (this.frontPoints !== null && this.frontPoints < this.uploaded) {
      this.paintMore(this.front, this.frontPoints, this.look());  // what arrived
      this.frontPoints = Math.min(this.uploaded, this.frontPoints + FULL_POINTS_PER_FRAME);
    }
    this.drawn = this.frontPoints === null ? 0 : this.frontPoints;
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    gl.viewport(0, 0, this.canvas.width, this.canvas.height);
    gl.useProgram(this.imageProgram);
    gl.bindTexture(gl.TEXTURE_2D, this.front.texture);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
    this.paintTool(this.transform());
    const isBehind = this.frontPoints !== null && this.frontPoints < this.uploaded;
    if (isUploading || isBehind || this.refining) {
      setTimeout(() => this.draw(), isTurning ? TURNING_MS / 4 : 0);
    } else if (this.isLinesStale) {
      setTimeout(() => this.draw(), RECOLOUR_MS / 4);
    }
  }

  // A level of detail (``points`` in ``vao``), alone in the image shown, at 1/``scale`` of
  // the canvas's size.
  paintLod(look, scale = 1, vao = this.lodVao, points = this.lodUploaded) {
    this.clearImage(this.front, look, scale);
    this.paintPath(vao, 0, points, look);
    this.frontPoints = null;
    this.isLodGrown = false;
    this.turningLod = scale === 1 ? 0 : points;
  }

  // One frame's part of the whole toolpath into the second image; when it is all there,
  // the second image is shown.
  refine() {
    const refining = this.refining;
    if (refining.points === 0) this.clearImage(this.back, refining.look);
    this.paintMore(this.back, refining.points, refining.look);
    refining.points = Math.min(this.uploaded, refining.points + FULL_POINTS_PER_FRAME);
    if (refining.points < this.uploaded) return;
    [this.front, this.back] = [this.back, this.front];
    this.frontPoints = refining.points;
    this.refining = null;
  }

  // The toolpath from point ``from`` on (FULL_POINTS_PER_FRAME of it at most) on top of
  // what ``image`` holds.
  paintMore(image, from, look) {
    const gl = this.gl;
    const first = Math.max(0, from - 1);  // the segment that joins the part before
    const count = Math.min(this.uploaded, from + FULL_POINTS_PER_FRAME) - first;
    gl.bindFramebuffer(gl.FRAMEBUFFER, image.framebuffer);
    gl.viewport(0, 0, image.width, image.height);
    this.paintPath(this.pathVao, first, count, look);
  }

  // ``image`` as big as the canvas (1/``scale`` of it), cleared, with the machine's limits.
  clearImage(image, look, scale = 1) {
    const gl = this.gl;
    const width = Math.max(1, Math.round(this.canvas.width / scale));
    const height = Math.max(1, Math.round(this.canvas.height / scale));
    if (image.width !== width || image.height !== height) {
      image.width = width;
      image.height = height;
      gl.bindTexture(gl.TEXTURE_2D, image.texture);
      gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA8, image.width, image.height, 0, gl.RGBA, gl.UNSIGNED_BYTE, null);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, scale === 1 ? gl.NEAREST : gl.LINEAR);
      gl.bindFramebuffer(gl.FRAMEBUFFER, image.framebuffer);
      gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, image.texture, 0);
    }
    gl.bindFramebuffer(gl.FRAMEBUFFER, image.framebuffer);
    gl.viewport(0, 0, image.width, image.height);
    gl.clearColor(...this.colors.background);
    gl.clear(gl.COLOR_BUFFER_BIT);
    if (this.limits) this.plainLines(limitEdges(this.limits), look.transform, this.colors.limits);
  }

  paintPath(vao, first, count, look) {
    const gl = this.gl, colors = this.colors, uniforms = this.uniforms;
    if (count < 2) return;
    gl.useProgram(this.pathProgram);
    gl.uniformMatrix4fv(uniforms.transform, false, look.transform);
    gl.uniform1f(uniforms.current, look.current);
    gl.uniform1f(uniforms.selected, look.selected);
    gl.uniform4fv(uniforms.rapidColor, colors.rapid);
    gl.uniform4fv(uniforms.feedColor, colors.feed);
    gl.uniform4fv(uniforms.doneColor, colors.done);
    gl.uniform4fv(uniforms.selectedColor, colors.selected);
    gl.bindVertexArray(vao);
    gl.drawArrays(gl.LINE_STRIP, first, count);
    gl.bindVertexArray(null);
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
    this.pending = [];
    const records = this.pieces.map((data) => new DataView(data));
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
      for (const view of records) {
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

// Whether the card is too slow for the level of detail while the view turns: a software
// renderer is from the start; another once the shortest of the last PACE_SAMPLES
// intervals between turning frames (a drag moves the view every frame of the page; a fast
// card keeps up) is over SLOW_TURN_FRAME_MS. Once slow, always slow: the card does not get
// faster, and the coarse level's pace would say nothing about the other's.
export class TurnPace {
  constructor(isSlow = false) {
    this.isSlow = isSlow;
    this.last = -Infinity;
    this.intervals = [];
  }

  frame(time) {
    if (time - this.last < 4 * TURNING_MS) {  // (longer: the hand paused)
      this.intervals.push(time - this.last);
      if (this.intervals.length > PACE_SAMPLES) this.intervals.shift();
      this.isSlow ||= this.intervals.length === PACE_SAMPLES
        && Math.min(...this.intervals) > SLOW_TURN_FRAME_MS;
    }
    this.last = time;
  }
}

// Whether the browser draws WebGL on the CPU (its own SwiftShader, Mesa's llvmpipe, ...).
export function isSoftwareCard(gl) {
  const info = gl.getExtension("WEBGL_debug_renderer_info");
  const name = gl.getParameter(info ? info.UNMASKED_RENDERER_WEBGL : gl.RENDERER);
  return /swiftshader|llvmpipe|softpipe|software|basic render/i.test(String(name));
}

// Records (RECORD) in ``buffer`` as the path program's inputs, in ``vao``.
function bindRecords(gl, vao, buffer) {
  gl.bindVertexArray(vao);
  gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
  gl.enableVertexAttribArray(0);
  gl.vertexAttribPointer(0, 3, gl.FLOAT, false, RECORD, 0);
  gl.enableVertexAttribArray(1);
  gl.vertexAttribIPointer(1, 1, gl.UNSIGNED_INT, RECORD, 12);
  gl.bindVertexArray(null);
}

// An image (a texture and its framebuffer); sized when first drawn into.
function newImage(gl) {
  return { texture: gl.createTexture(), framebuffer: gl.createFramebuffer(), width: 0, height: 0 };
}

// The length of the diagonal of ``bounds`` ([xmin, ymin, zmin, xmax, ymax, zmax]).
function diagonal(bounds) {
  if (!bounds) return 1;
  return Math.max(Math.hypot(bounds[3] - bounds[0], bounds[4] - bounds[1], bounds[5] - bounds[2]), 1e-3);
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

