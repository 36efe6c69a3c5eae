// The program: the file list, Run/Pause/Resume/Step, the run's progress, the listing and
// the preview, side by side or one at a time.
//
// The listing is virtual: only the lines in view exist in the page, decoded from the
// program's bytes when they come into view, so a program of millions of lines loads and
// scrolls as fast as a short one. Program text and toolpath are fetched, and the preview
// drawn, by a worker thread (program-worker.js) for the open program (the server's
// "program" messages name it by number: a newer program makes the page drop whatever is
// still coming of an older one, so a listing never shows another program's lines).

import { $, duration, el, fetchJson, on, setText, state, withToken } from "./core.js";
import { send } from "./link.js";
import { executingLine } from "./machine.js";
import { notice } from "./notices.js";
import { CAMERAS } from "./camera.js";
import { Preview } from "./preview.js";

const ROW_PX = 20;  // the height of a listing line (style.css: .listing-row)
const MAX_SPACE_PX = 8_000_000;  // browsers cap an element's height; more lines: scaled
const FOLLOW_PAUSE_MS = 4000;  // after the operator scrolls, the listing stops following
const decoder = new TextDecoder("utf-8");

const worker = new Worker("/static/js/program-worker.js", { type: "module" });
const preview = new Preview($("preview"), worker);
let number = null;  // the open program's analysis number
let text = null;  // {bytes: Uint8Array, starts: Uint32Array, count}
let selected = 0;
let errorLine = 0, errorText = "";
let reportedNumber = null;  // the program whose load error became a notice
let lastScrollByOperator = 0;
let isScrollByPage = false;

// ------------------------------------------------------------------ the open program
on("program", (message) => {
  if (message.number !== number) {
    number = message.number;
    text = null;
    $("listing").dataset.lines = 0;  // until this program's text is here
    selected = 0;
    preview.reset();
    drawListing();
    $("program-file").replaceChildren(el("bdi", { textContent: message.file || "No program open" }));
    $("program-file").title = message.file || "";
    worker.postMessage({ type: "program", number,
      textUrl: withToken(`/api/program/text?number=${number}`),
      previewUrl: withToken(`/api/preview/data?number=${number}`) });
    if (message.name_in_prefix) selectInList(message.name_in_prefix);
  }
  worker.postMessage({ type: "points", number, points: message.preview_points });
  const error = message.preview_error || (message.failure ? { line: 0, message: message.failure } : null);
  errorLine = error ? error.line : 0;
  errorText = error ? error.message : "";
  if (error && message.is_preview_done && reportedNumber !== number) {
    reportedNumber = number;
    notice("error", `${fileName(message.file)}: ${error.line ? `line ${error.line}: ` : ""}${error.message}`);
    if (error.line) scrollToLine(error.line, true);
  }
  showAnalysis(message);
  drawListing();
});

function fileName(path) { return (path || "").split("/").pop(); }

worker.onmessage = (event) => {
  const message = event.data;
  if (message.number !== number) return;
  if (message.type === "text") {
    const starts = new Uint32Array(message.starts);
    text = { bytes: new Uint8Array(message.bytes), starts, count: starts.length - 1 };
    rows.replaceChildren();  // rows of the program before, whatever their lines
    $("listing").dataset.lines = text.count;
    followLine(true);
  } else if (message.type === "preview") {
    preview.drawn(message);
  } else if (message.type === "failed") {
    notice("error", `${message.what}: ${message.message}`);
  }
};

function showAnalysis(message) {
  const parts = [];
  if (message.is_preview_done) {
    parts.push(`${message.preview_points.toLocaleString()} points`);
    if (message.is_truncated) parts.push("preview cut short (too many moves)");
  } else {
    parts.push(`reading… ${message.preview_points.toLocaleString()} points`);
  }
  const estimate = message.estimate;
  if (estimate) {
    let words = `estimated run time ${duration(estimate.total_s)}`;
    if (estimate.stops) words += ` + ${estimate.stops} program stop${estimate.stops > 1 ? "s" : ""}`;
    if (estimate.tool_changes) words += ` + ${estimate.tool_changes} tool change${estimate.tool_changes > 1 ? "s" : ""}`;
    parts.push(words);
  } else if (message.is_preview_done && !message.failure) {
    parts.push(`estimating… ${duration(message.estimate_progress_s)} so far`);
  }
  if (errorText) parts.push(`error${errorLine ? ` on line ${errorLine}` : ""}: ${errorText}`);
  $("analysis").textContent = parts.join(" · ");
  $("analysis").classList.toggle("bad", Boolean(errorText));
  $("preview-status").textContent = errorText ? `line ${errorLine}: ${errorText}` : "";
}

// ------------------------------------------------------------------ listing
const listing = $("listing");
const rows = listing.querySelector(".listing-rows");
const space = listing.querySelector(".listing-space");

function lineText(line) {  // 1-based
  const start = text.starts[line - 1], end = text.starts[line];
  let value = decoder.decode(text.bytes.subarray(start, end));
  value = value.replace(/\r?\n$/, "");
  return value;
}

// Scroll position <-> first line shown (scaled when the lines would be too tall).
function spaceHeight() { return Math.min((text ? text.count : 0) * ROW_PX, MAX_SPACE_PX); }
function firstLineAt(scrollTop) {
  const count = text ? text.count : 0;
  const visible = Math.ceil(listing.clientHeight / ROW_PX);
  if (count * ROW_PX <= MAX_SPACE_PX) return scrollTop / ROW_PX;
  const range = Math.max(spaceHeight() - listing.clientHeight, 1);
  return (scrollTop / range) * Math.max(count - visible, 0);
}
function scrollTopFor(firstLine) {
  const count = text ? text.count : 0;
  const visible = Math.ceil(listing.clientHeight / ROW_PX);
  if (count * ROW_PX <= MAX_SPACE_PX) return firstLine * ROW_PX;
  return (firstLine / Math.max(count - visible, 1)) * Math.max(spaceHeight() - listing.clientHeight, 1);
}

let isDrawPending = false;
let follow = null;  // null, or whether to bring the executing line into view by force
function drawListing() {
  if (isDrawPending) return;
  isDrawPending = true;
  requestAnimationFrame(() => { isDrawPending = false; paintListing(); });
}

function paintListing() {
  const height = `${spaceHeight()}px`;
  if (space.style.height !== height) space.style.height = height;
  if (!text) { rows.replaceChildren(); return; }
  if (follow !== null) {  // here, in the frame: reading the layout costs nothing more
    const line = executingLine(state.status);
    if (line) scrollToLine(line, follow);
    follow = null;
  }
  const first = firstLineAt(listing.scrollTop);
  const firstIndex = Math.floor(first);
  const count = Math.min(Math.ceil(listing.clientHeight / ROW_PX) + 2, text.count - firstIndex);
  while (rows.children.length < count) {
    rows.append(el("div", { className: "listing-row" }, el("span", { className: "number" }), el("span", { className: "code" })));
  }
  while (rows.children.length > count) rows.lastChild.remove();
  rows.style.transform = `translateY(${-(first - firstIndex) * ROW_PX}px)`;
  const current = executingLine(state.status);
  for (let i = 0; i < count; i++) {
    const line = firstIndex + i + 1;
    const row = rows.children[i];
    if (row.dataset.line !== String(line)) {
      row.dataset.line = line;
      setText(row.children[0], line);
      setText(row.children[1], lineText(line) || " ");
    }
    const className = "listing-row" +
      (line === current ? " current" : "") +
      (line === selected ? " selected" : "") +
      (line === errorLine ? " error" : "");
    if (row.className !== className) row.className = className;
    const title = line === errorLine ? errorText : "";
    if (row.title !== title) row.title = title;
  }
}

listing.addEventListener("scroll", () => {
  if (!isScrollByPage) lastScrollByOperator = performance.now();
  isScrollByPage = false;
  drawListing();
}, { passive: true });
new ResizeObserver(drawListing).observe(listing);

rows.addEventListener("click", (event) => {
  const row = event.target.closest(".listing-row");
  if (!row) return;
  selected = Number(row.dataset.line);
  preview.setLines(preview.state.current, selected);
  drawListing();
});
rows.addEventListener("dblclick", (event) => {
  const row = event.target.closest(".listing-row");
  if (row) $("run-line").value = row.dataset.line;  // run from here
});

function scrollToLine(line, isForced = false) {
  if (!text || !line) return;
  if (!isForced && performance.now() - lastScrollByOperator < FOLLOW_PAUSE_MS) return;
  const visible = listing.clientHeight / ROW_PX;
  const first = firstLineAt(listing.scrollTop);
  if (!isForced && line - 1 >= first + 2 && line <= first + visible - 2) return;  // in view
  const top = scrollTopFor(Math.max(line - 1 - visible / 2, 0));
  if (Math.abs(listing.scrollTop - top) > 1) {
    isScrollByPage = true;
    listing.scrollTop = top;
  }
}

// Bring the executing line into view at the next frame (forced: even if the operator
// scrolled away a moment ago).
function followLine(isForced = false) {
  follow = follow || isForced;
  drawListing();
}

// ------------------------------------------------------------------ status
let lastLine = -1;
on("status", (changes) => {
  const s = state.status;
  const line = executingLine(s);
  const isRunning = s.interp_state && s.interp_state !== "IDLE";
  preview.setLines(isRunning ? line : 0, selected);
  if ("work" in changes || "machine" in changes) preview.setTool(toolPosition(s), limitsBox(s));
  if (line !== lastLine) {
    lastLine = line;
    followLine();
  }
  showProgress(s.job);
  $("optional-stop").classList.toggle("on", Boolean(s.is_optional_stop));
  $("block-delete").classList.toggle("on", Boolean(s.is_block_delete));
  document.body.classList.toggle("running", Boolean(isRunning));
});

function toolPosition(s) {
  const axes = s.axes || "";
  return [..."XYZ"].map((letter) => (axes.includes(letter) ? s.work[axes.indexOf(letter)] || 0 : 0));
}

// The machine's limits, shifted into work coordinates by the offsets in force now.
function limitsBox(s) {
  const limits = (state.config && state.config.limits) || {};
  const axes = s.axes || "";
  const box = [];
  for (const letter of "XYZ") {
    const index = axes.indexOf(letter);
    const range = limits[letter];
    if (!range || index < 0 || s.work[index] === null || s.machine[index] === null) return null;
    const shift = s.work[index] - s.machine[index];
    box.push([range[0] + shift, range[1] + shift]);
  }
  return box;
}

function showProgress(job) {
  $("progress").hidden = !job;
  $("bar-progress").hidden = !job;
  if (!job) return;
  const percent = job.progress === null ? null : Math.round(job.progress * 1000) / 10;
  const bar = $("progress").querySelector(".progress-bar span");
  bar.style.width = `${percent ?? 0}%`;
  $("bar-progress").querySelector("span").style.width = `${percent ?? 0}%`;
  $("bar-progress").title = percent === null ? "running" : `${percent} %`;
  const parts = [percent === null ? "progress: estimating…"
    : job.progress_by === "lines" ? `${percent.toFixed(1)} % of the lines (estimating the time…)`
      : `${percent.toFixed(1)} %`,
    `${duration(job.elapsed_s)} elapsed`];
  if (job.remaining_s !== null) parts.push(`about ${duration(job.remaining_s)} left`);
  if (job.estimate_s !== null) parts.push(`estimate ${duration(job.estimate_s)}`);
  setText($("progress-text"), parts.join(" · "));
}

// ------------------------------------------------------------------ files and run
async function loadFiles() {
  try {
    const answer = await fetchJson("/api/files");
    const chosen = state.program && state.program.name_in_prefix;
    $("program-list").replaceChildren(...answer.files.map((name) => new Option(name, name)));
    if (chosen) selectInList(chosen);
  } catch (error) {
    notice("error", `program list: ${error.message}`);
  }
}

function selectInList(name) {  // the list shows the loaded program, not the first one
  const list = $("program-list");
  if (![...list.options].some((option) => option.value === name)) list.append(new Option(name, name));
  list.value = name;
}

$("program-list").onchange = () => $("program-list").blur();
$("program-open").onclick = () => {
  const file = $("program-list").value;
  if (file) send("open", { file });
};
$("program-refresh").onclick = loadFiles;
$("run").onclick = () => {  // "from line": a whole line number, or empty for the start
  const value = $("run-line").value.trim();
  if (value && !/^[0-9]+$/.test(value)) notice("error", `'${value}' is not a line number`);
  else send("run", { line: value ? Number(value) : 0 });
};
$("pause").onclick = () => send("pause");
$("resume").onclick = () => send("resume");
$("step").onclick = () => send("step");
$("optional-stop").onclick = () => send("optional_stop", { on: !state.status.is_optional_stop });
$("block-delete").onclick = () => send("block_delete", { on: !state.status.is_block_delete });

$("program-upload").onchange = async (event) => {
  const file = event.target.files[0];
  if (!file) return;
  const form = new FormData();
  form.append("file", file);
  const response = await fetch(withToken("/api/upload"), { method: "POST", body: form });
  event.target.value = "";
  if (!response.ok) { notice("error", await response.text()); return; }
  const answer = await response.json();
  await loadFiles();
  selectInList(answer.file);
  send("open", { file: answer.file });
};

// ------------------------------------------------------------------ listing and preview
function setSplit(choice) {
  $("program-split").className = `program-split ${choice}`;
  for (const button of $("split").children) button.classList.toggle("on", button.dataset.split === choice);
  localStorage.setItem("cnc.split", choice);
  drawListing();
  preview.setVisible(choice !== "listing");
}
for (const button of $("split").children) button.onclick = () => setSplit(button.dataset.split);
document.querySelectorAll("[data-camera]").forEach((button) => {
  button.onclick = () => {
    if (button.dataset.camera === "fit") preview.fit();
    else preview.setCamera(button.dataset.camera);
  };
});

on("config", (config) => {
  loadFiles();
  if (config.is_lathe) { CAMERAS.top = CAMERAS.lathe; preview.setCamera("lathe"); }
});
on("theme", () => preview.sendColors());  // its colours come from the theme
setSplit(localStorage.getItem("cnc.split") || "both");

export function openProgramName() { return state.program ? state.program.name_in_prefix : null; }
export { preview, loadFiles };
