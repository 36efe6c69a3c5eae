// The worker thread behind the program view: it fetches the open program's text and
// toolpath and draws the preview (renderer.js, on the canvas the page handed over), so
// that the page's own thread, which must answer STOP at once, never splits megabytes of
// text, reads millions of toolpath records, or waits for the graphics card.
//
// page -> worker:
//   {type: "canvas", canvas}                      the preview's OffscreenCanvas (once)
//   {type: "program", number, textUrl, previewUrl} a program to show (drops any older one)
//   {type: "points", number, points}               the server has this much toolpath
//   {type: "set", ...}                             view, size, colours, lines, tool ...
// worker -> page:
//   {type: "text", number, bytes, starts}          the text and where each line starts
//                                                  (transferred: the page decodes only
//                                                  the lines it shows)
//   {type: "preview", number, points, drawn, renderer, frames, bounds}
//   {type: "failed", number, what, message}

import { Renderer } from "./renderer.js";

const RECORD = 16;
let renderer = null;
let number = null;  // the program shown; anything older is dropped
let fetched = 0;  // toolpath records fetched for it
let wanted = 0;
let isFetching = false;
let previewUrl = "";
let bounds = null;

function report(drawing) {
  self.postMessage({ type: "preview", number, bounds, ...drawing });
}

self.onmessage = (event) => {
  const message = event.data;
  if (message.type === "canvas") {
    renderer = new Renderer(message.canvas, report);
  } else if (message.type === "set") {
    if (renderer) renderer.set(message.changes);
  } else if (message.type === "program") {
    number = message.number;
    fetched = 0; wanted = 0; bounds = null; isFetching = false;
    previewUrl = message.previewUrl;
    if (renderer) renderer.reset();
    loadText(message);
  } else if (message.type === "points" && message.number === number) {
    wanted = Math.max(wanted, message.points);
    if (!isFetching) loadPreview(number);
  }
};

async function loadText(message) {
  try {
    const response = await fetch(message.textUrl);
    if (!response.ok) throw new Error(await response.text());
    const bytes = new Uint8Array(await response.arrayBuffer());
    if (message.number !== number) return;
    const starts = lineStarts(bytes);
    self.postMessage({ type: "text", number: message.number, bytes: bytes.buffer, starts: starts.buffer },
      [bytes.buffer, starts.buffer]);
  } catch (error) {
    self.postMessage({ type: "failed", number: message.number, what: "listing", message: String(error) });
  }
}

// Where each line starts, and the end (a last line without a newline counts).
function lineStarts(bytes) {
  let count = 0;
  for (let i = 0; i < bytes.length; i++) if (bytes[i] === 10) count++;
  const hasTail = bytes.length > 0 && bytes[bytes.length - 1] !== 10;
  const starts = new Uint32Array(count + (hasTail ? 1 : 0) + 1);
  let line = 1;
  for (let i = 0; i < bytes.length; i++) if (bytes[i] === 10) starts[line++] = i + 1;
  if (hasTail) starts[line++] = bytes.length;
  return starts.subarray(0, line).slice();
}

async function loadPreview(forNumber) {
  isFetching = true;
  try {
    while (forNumber === number && fetched < wanted) {
      const response = await fetch(`${previewUrl}&from=${fetched}`);
      if (forNumber !== number) return;
      if (!response.ok) throw new Error(await response.text());
      const data = await response.arrayBuffer();
      if (forNumber !== number || data.byteLength === 0) break;
      fetched += data.byteLength / RECORD;
      grow(new DataView(data));
      if (renderer) renderer.append(data, bounds);
    }
  } catch (error) {
    self.postMessage({ type: "failed", number: forNumber, what: "preview", message: String(error) });
  } finally {
    if (forNumber === number) isFetching = false;
  }
}

function grow(view) {
  bounds = bounds || [Infinity, Infinity, Infinity, -Infinity, -Infinity, -Infinity];
  for (let offset = 0; offset < view.byteLength; offset += RECORD) {
    for (let axis = 0; axis < 3; axis++) {
      const value = view.getFloat32(offset + 4 * axis, true);
      if (value < bounds[axis]) bounds[axis] = value;
      if (value > bounds[axis + 3]) bounds[axis + 3] = value;
    }
  }
}
