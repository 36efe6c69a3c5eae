// The toolpath preview, as the page sees it: the camera (drag turns, shift+drag or two
// fingers pan, the wheel zooms; Top, Front, Side, Iso, Fit), and what to draw, sent to the
// worker thread that draws (program-worker.js, renderer.js) on the canvas handed over to
// it. The page's thread never draws the toolpath: nothing drawn can hold up STOP.

import { CAMERAS, fitted, newView } from "./camera.js";

export class Preview {
  // ``worker``: program-worker.js, which is handed the canvas.
  constructor(canvas, worker) {
    this.canvas = canvas;
    this.worker = worker;
    this.view = newView();
    this.bounds = null;
    this.isMovedByOperator = false;  // turned, panned or zoomed since the toolpath came
    this.state = { current: 0, selected: 0 };
    if (canvas.transferControlToOffscreen) {
      const offscreen = canvas.transferControlToOffscreen();
      worker.postMessage({ type: "canvas", canvas: offscreen }, [offscreen]);
    } else {
      canvas.dataset.renderer = "none";  // a browser without OffscreenCanvas: no preview
    }
    this.listenToPointers();
    new ResizeObserver(() => this.sendSize()).observe(canvas);
    this.sendSize();
    this.sendColors();
    this.send({ view: this.view });
  }

  send(changes) { this.worker.postMessage({ type: "set", changes }); }

  sendSize() {
    const width = this.canvas.clientWidth, height = this.canvas.clientHeight;
    if (!width || !height) return;  // hidden: drawn again when shown
    this.size = [width, height];
    this.send({ width, height, ratio: window.devicePixelRatio || 1 });
    if (!this.isMovedByOperator) this.fit();
  }

  sendColors() {  // from the theme's CSS
    const style = getComputedStyle(this.canvas);
    const read = (name) => cssColor(style.getPropertyValue(name));
    this.send({ colors: {
      background: read("--preview-bg"), rapid: read("--path-rapid"), feed: read("--path-feed"),
      done: read("--path-done"), selected: read("--path-selected"), limits: read("--path-limits"),
      tool: read("--path-tool"),
    } });
  }

  // What the worker drew: {points, drawn, renderer, frames, lod, turningLod, bounds}.
  drawn(report) {
    this.canvas.dataset.points = report.points;
    this.canvas.dataset.drawn = report.drawn;
    this.canvas.dataset.frames = report.frames;  // ui_bench counts them
    this.canvas.dataset.lod = report.lod;  // (the level of detail's points, for ui_bench)
    this.canvas.dataset.turningLod = report.turningLod;  // (... drawn while the view turns)
    this.canvas.dataset.renderer = report.renderer;
    if (report.bounds && JSON.stringify(report.bounds) !== JSON.stringify(this.bounds)) {
      this.bounds = report.bounds;
      if (!this.isMovedByOperator) this.fit();  // the whole toolpath in view, as it grows
    }
  }

  reset() {
    this.bounds = null;
    this.isMovedByOperator = false;
    this.canvas.dataset.points = 0;
    this.canvas.dataset.drawn = 0;
  }

  setLines(current, selected) {
    if (current === this.state.current && selected === this.state.selected) return;
    this.state = { current, selected };
    this.send(this.state);
  }

  setTool(tool, limits) { this.send({ tool, limits }); }
  setVisible(isVisible) { this.send({ isVisible }); if (isVisible) this.sendSize(); }

  setCamera(name) {
    const camera = CAMERAS[name];
    if (camera) [this.view.yaw, this.view.pitch, this.view.roll] = camera;
    this.fit();
  }

  fit() {
    const [width, height] = this.size || [400, 300];
    this.view = fitted(this.view, this.bounds, width, height);
    this.send({ view: this.view });
  }

  listenToPointers() {
    const canvas = this.canvas;
    const pointers = new Map();
    const turned = () => {
      this.isMovedByOperator = true;
      this.send({ view: this.view, turned: true });
    };
    canvas.addEventListener("pointerdown", (event) => {
      canvas.setPointerCapture(event.pointerId);
      pointers.set(event.pointerId, [event.clientX, event.clientY]);
      this.send({ isHeld: true });
    });
    canvas.addEventListener("pointermove", (event) => {
      const last = pointers.get(event.pointerId);
      if (!last) return;
      const dx = event.clientX - last[0], dy = event.clientY - last[1];
      pointers.set(event.pointerId, [event.clientX, event.clientY]);
      const view = this.view;
      if (event.shiftKey || pointers.size > 1) {
        view.x += dx / view.scale / pointers.size;
        view.y -= dy / view.scale / pointers.size;
      } else {
        view.yaw += dx * 0.01;
        view.pitch = Math.max(-Math.PI, Math.min(0, view.pitch + dy * 0.01));
      }
      turned();
    });
    const release = (event) => {
      pointers.delete(event.pointerId);
      if (!pointers.size) this.send({ isHeld: false });
    };
    canvas.addEventListener("pointerup", release);
    canvas.addEventListener("pointercancel", release);
    canvas.addEventListener("wheel", (event) => {
      event.preventDefault();
      this.view.scale *= event.deltaY < 0 ? 1.15 : 1 / 1.15;
      turned();
    }, { passive: false });
  }
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
