// A worker thread that fetches the open program for the page, so that the page's own
// thread (which must answer STOP at once) never splits megabytes of text or reads
// millions of toolpath records.
//
// page -> worker: {type: "program", number, url}: fetch the text, find where each line
//   starts; {type: "preview", number, url, points}: fetch the toolpath records from the
//   last one fetched up to ``points`` (what the server has so far).
// worker -> page: {type: "text", number, bytes, starts} (transferred, not copied: the page
//   decodes only the lines it shows); {type: "chunk", number, first, data, bounds} for each
//   piece of toolpath (16-byte records, cnc/ui/web/preview.py), with the bounds so far;
//   {type: "failed", number, what, message}.

const RECORD = 16;
let number = null;  // the program being loaded; anything older is dropped
let fetched = 0;  // toolpath records fetched for it
let isFetching = false;
let wanted = 0;
let previewUrl = "";
let bounds = null;

self.onmessage = (event) => {
  const message = event.data;
  if (message.number !== number) {
    number = message.number;
    fetched = 0; wanted = 0; bounds = null; isFetching = false;
  }
  if (message.type === "program") loadText(message);
  else if (message.type === "preview") {
    previewUrl = message.url;
    wanted = Math.max(wanted, message.points);
    if (!isFetching) loadPreview(number);
  }
};

async function loadText(message) {
  try {
    const response = await fetch(message.url);
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

// Where each line starts (a last line without a newline counts; an empty file has none).
function lineStarts(bytes) {
  let count = 0;
  for (let i = 0; i < bytes.length; i++) if (bytes[i] === 10) count++;
  const hasTail = bytes.length > 0 && bytes[bytes.length - 1] !== 10;
  const starts = new Uint32Array(count + (hasTail ? 1 : 0) + 1);  // + the end
  let line = 1;
  starts[0] = 0;
  for (let i = 0; i < bytes.length; i++) if (bytes[i] === 10) starts[line++] = i + 1;
  if (hasTail) starts[line++] = bytes.length;
  return starts.subarray(0, line).slice();  // line - 1 lines, and the end
}

async function loadPreview(forNumber) {
  isFetching = true;
  try {
    while (forNumber === number && fetched < wanted) {
      const response = await fetch(`${previewUrl}&from=${fetched}`);
      if (forNumber !== number) return;
      if (!response.ok) throw new Error(await response.text());
      const data = await response.arrayBuffer();
      if (data.byteLength === 0) break;
      const first = fetched;
      fetched += data.byteLength / RECORD;
      grow(new DataView(data));
      self.postMessage({ type: "chunk", number: forNumber, first, data, bounds }, [data]);
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
