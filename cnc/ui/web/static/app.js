// The operator page: shows the status the server pushes over /ws and sends commands.
// No framework, no build step. Protocol: see cnc/ui/web/server.py.
"use strict";

const token = new URLSearchParams(location.search).get("token");
const $ = (id) => document.getElementById(id);

let config = null;     // {axes, increments, jog_speed, overrides, macros, is_control, ...}
let status = {};       // the last complete status (diffs are merged in)
let socket = null;
let nextId = 1;
const pending = new Map();  // command id -> callback(result)
let programFile = null;     // the file whose listing is shown

// ------------------------------------------------------------------ helpers
function withToken(path) {
  return token ? `${path}${path.includes("?") ? "&" : "?"}token=${encodeURIComponent(token)}` : path;
}

// A number typed by the operator: ',' or '.' as decimal separator (at most one), spaces as
// thousands separators (GUI-003); null if it is not one.
function parseDecimal(text) {
  const compact = String(text).trim().replace(/ /g, "");
  if ((compact.match(/[.,]/g) || []).length > 1) return null;
  if (!/^[+-]?([0-9]+[.,]?[0-9]*|[.,][0-9]+)$/.test(compact)) return null;
  return parseFloat(compact.replace(",", "."));
}

function places() { return config ? config.places : 3; }

function fixed(value, digits = places()) {
  return value === null || value === undefined ? "—" : Number(value).toFixed(digits);
}

function notice(kind, text) {
  const box = document.createElement("div");
  box.className = `notice ${kind}`;
  const words = document.createElement("span");
  words.textContent = text;
  const close = document.createElement("button");
  close.textContent = "×";
  close.title = "Dismiss";
  close.onclick = () => box.remove();
  box.append(words, close);
  $("notices").prepend(box);
  while ($("notices").children.length > 8) $("notices").lastChild.remove();
}

// [DISPLAY] MESSAGE_* / MULTIMESSAGE_* dialogs, shown while the server says one is open
// (its HAL pin rose); the first answer from any page closes it in all of them.
function showDialog(d) {
  closeDialog(d.name);
  const box = document.createElement("div");
  box.className = `dialog ${d.icon.toLowerCase()}`;
  box.dataset.name = d.name;
  box.setAttribute("role", "alertdialog");
  if (d.title) box.append(Object.assign(document.createElement("h3"), { textContent: d.title }));
  box.append(Object.assign(document.createElement("p"), { textContent: d.text }));
  if (d.details) {
    const more = document.createElement("details");
    more.append(Object.assign(document.createElement("summary"), { textContent: "Details" }), d.details);
    box.append(more);
  }
  const answers = { ok: [["OK", true]], yesno: [["Yes", true], ["No", false]], none: [] }[d.kind] || [];
  const row = document.createElement("div");
  row.className = "row";
  for (const [label, isYes] of answers) {
    const button = Object.assign(document.createElement("button"), { textContent: label });
    button.onclick = () => send("answer", { name: d.name, is_yes: isYes });
    row.append(button);
  }
  box.append(row);
  $("dialogs").append(box);
}

function closeDialog(name) {
  for (const box of [...$("dialogs").children]) if (box.dataset.name === name) box.remove();
}

// Send a command; the promise gets the server's result {status, message}.
function send(cmd, args = {}) {
  return new Promise((resolve) => {
    if (!socket || socket.readyState !== WebSocket.OPEN) {
      notice("error", `${cmd}: not connected to the server`);
      resolve({ status: "ERROR", message: "not connected" });
      return;
    }
    const id = nextId++;
    pending.set(id, (result) => {
      // The controller's own reason arrives as a notice; other failures are shown here.
      if (result.status !== "DONE" && !result.is_reported) notice("error", result.message);
      resolve(result);
    });
    socket.send(JSON.stringify({ cmd, id, ...args }));
  });
}

// ------------------------------------------------------------------ connection
function connect() {
  const scheme = location.protocol === "https:" ? "wss" : "ws";
  socket = new WebSocket(withToken(`${scheme}://${location.host}/ws`));
  socket.onmessage = (event) => receive(JSON.parse(event.data));
  socket.onopen = () => { $("link").textContent = "online"; $("link").className = "pill good"; };
  socket.onclose = () => {
    $("link").textContent = "offline";
    $("link").className = "pill bad";
    pending.forEach((done) => done({ status: "ERROR", message: "connection lost" }));
    pending.clear();
    setTimeout(connect, 1000);
  };
}

function receive(message) {
  if (message.type === "config") setup(message.data);
  else if (message.type === "status") update(message.data);
  else if (message.type === "notice") notice(message.kind, message.text);
  else if (message.type === "history") showHistory(message.lines);
  else if (message.type === "dialog") showDialog(message);
  else if (message.type === "dialog_close") closeDialog(message.name);
  else if (message.type === "result") {
    const done = pending.get(message.id);
    pending.delete(message.id);
    if (done) done(message);
    else if (message.status !== "DONE" && !message.is_reported) notice("error", message.message);
  }
}

// ------------------------------------------------------------------ building the page
function setup(data) {
  config = data;
  document.title = data.title || "cnc";
  // [DISPLAY]POSITION_OFFSET = MACHINE: machine coordinates are the big numbers.
  document.body.classList.toggle("machine-first", !data.is_position_relative);
  $("machine-name").textContent = data.machine;
  document.body.classList.toggle("read-only", !data.is_control);
  document.body.classList.toggle("lathe", data.is_lathe);
  buildJog(data.axes);
  setJogChoices("increment", "jog-speed", data.increments, data.jog_speed);
  setJogChoices("angular-increment", "angular-speed", data.angular_increments, data.angular_jog_speed);
  $("angular-jog").hidden = !/[ABC]/.test(data.axes);
  $("spindle-speed").value = data.spindle.default;
  if (data.is_lathe) {  // a lathe: arrows jog Z (left/right) and X (up/down), XZ preview
    Object.assign(JOG_KEYS, {
      ArrowLeft: ["Z", -1], ArrowRight: ["Z", 1], ArrowDown: ["X", 1], ArrowUp: ["X", -1],
    });
    [view.yaw, view.pitch, view.roll] = VIEWS.lathe;
    VIEWS.top = VIEWS.lathe;  // "Top" of a lathe: the XZ plane
  }
  setRange("feedrate", 0, data.overrides.feed_max);
  setRange("rapidrate", 0, data.overrides.rapid_max);
  setRange("spindle-override", data.overrides.spindle_min, data.overrides.spindle_max);
  $("macros").replaceChildren(...data.macros.map((macro, index) => {
    const button = document.createElement("button");
    button.textContent = macro.label;
    button.title = macro.commands;
    button.onclick = () => send("macro", { index });
    return button;
  }));
  showHistory(data.mdi_history);
  loadFiles();
}

// A step choice and a speed slider for linear or angular jogs (GUI-009, GUI-012).
function setJogChoices(stepId, speedId, steps, speeds) {
  $(stepId).replaceChildren(...steps.map((step) => new Option(step.label, step.distance)));
  const speed = $(speedId);
  speed.min = speeds.min; speed.max = speeds.max; speed.value = speeds.default;
  speed.oninput = () => { $(`${speedId}-value`).textContent = speed.value; };
  speed.oninput();
}

function setRange(id, min, max) {
  const slider = $(id);
  slider.min = min; slider.max = max;
  let timer = null;
  slider.oninput = () => {
    $(`${id}-value`).textContent = `${slider.value}%`;
    clearTimeout(timer);  // send once the slider rests for a moment, and on release
    timer = setTimeout(() => send(id.replace("-", "_"), { percent: Number(slider.value) }), 150);
  };
}

// The DRO: one row per axis, or per joint ("J0" ...) when the joint view is chosen or the
// machine is not homed and its joints are not its axes. Home buttons use the row's joint
// (for axes: the place of the letter, as on trivial kinematics).
let isJointViewChosen = false;
let droKind = null;

function buildDro(labels, kind) {
  droKind = kind;
  const body = $("dro").tBodies[0];
  body.replaceChildren();
  labels.forEach((label, joint) => {
    const row = body.insertRow();
    row.dataset.axis = label;
    row.innerHTML = `<th>${label}<span class="homed" title="homed">●</span></th>` +
      "<td class=work></td><td class=machine></td><td class=dtg></td>" +
      "<td><button class=home>Home</button></td>" +
      "<td><button class=touch title='Set the work position (G10 L20)'>Touch</button></td>";
    row.querySelector(".home").onclick = () => send("home", { joint });
    const touch = row.querySelector(".touch");
    touch.hidden = kind === "joints";
    touch.onclick = () => {
      const answer = prompt(`${label} work position:`, "0");
      if (answer === null) return;
      const value = parseDecimal(answer);
      if (value === null) notice("error", `'${answer}' is not a number`);
      else send("touch_off", { axis: label, value });
    };
  });
}

function showDro(s) {
  const axes = [...(s.axes || "")];
  const isJoints = isJointViewChosen || (!s.is_all_homed && s.homed.length !== axes.length);
  const labels = isJoints ? s.homed.map((_, index) => `J${index}`) : axes;
  const kind = isJoints ? "joints" : "axes";
  const rows = $("dro").tBodies[0].rows;
  if (kind !== droKind || rows.length !== labels.length) buildDro(labels, kind);
  $("dro-joints").classList.toggle("on", isJoints);
  labels.forEach((_, index) => {
    const row = rows[index];
    row.querySelector(".work").textContent = fixed(isJoints ? s.joint_position[index] : s.work[index]);
    row.querySelector(".machine").textContent = isJoints ? "" : fixed(s.machine[index]);
    row.querySelector(".dtg").textContent = isJoints ? "" : fixed(s.dtg[index]);
    row.classList.toggle("is-homed", Boolean(s.homed[index]));
    row.classList.toggle("is-homing", Boolean(s.homing[index]));
  });
}

$("dro-joints").onclick = () => {
  isJointViewChosen = !isJointViewChosen;
  showDro(status);
};

// Jog buttons: press and hold to jog continuously, or one step with a step selected.
function buildJog(axes) {
  const grid = $("jog-buttons");
  grid.replaceChildren();
  for (const letter of axes) {
    for (const direction of [-1, 1]) {
      const button = document.createElement("button");
      button.textContent = `${letter}${direction < 0 ? "−" : "+"}`;
      button.className = "jog";
      button.dataset.axis = letter;
      button.onpointerdown = (event) => { button.setPointerCapture(event.pointerId); jogStart(letter, direction); };
      for (const end of ["pointerup", "pointercancel", "lostpointercapture"]) {
        button.addEventListener(end, () => jogStop(letter));
      }
      grid.append(button);
    }
  }
}

const jogging = new Set();  // axes in a continuous jog

function jogStart(axis, direction) {
  const isAngular = "ABC".includes(axis);
  const speed = Number($(isAngular ? "angular-speed" : "jog-speed").value);
  const distance = Number($(isAngular ? "angular-increment" : "increment").value);
  if (distance > 0) {
    send("jog", { action: "increment", axis, direction, speed, distance });
  } else if (!jogging.has(axis)) {
    jogging.add(axis);
    send("jog", { action: "start", axis, direction, speed });
  }
}

function jogStop(axis) {
  if (jogging.delete(axis)) send("jog", { action: "stop", axis });
}

function stopAllJogs() { [...jogging].forEach(jogStop); }

// ------------------------------------------------------------------ showing the status
function update(changes) {
  Object.assign(status, changes);
  const s = status;
  $("link").textContent = s.is_connected ? "online" : "controller offline";
  $("link").className = s.is_connected ? "pill good" : "pill bad";
  if (!s.is_connected) return;
  $("task-state").textContent = s.task_state;
  $("task-mode").textContent = s.task_mode;
  $("interp-state").textContent = s.interp_state + (s.is_paused ? " (paused)" : "");
  $("estop").classList.toggle("active", s.is_estop);
  $("power").classList.toggle("on", s.task_state === "ON");
  $("g5x").textContent = s.g5x;
  showDro(s);
  $("gcodes").textContent = s.gcodes || "—";
  $("mcodes").textContent = s.mcodes || "—";
  $("feed").textContent = s.feed;
  $("speed").textContent = s.speed;
  $("velocity").textContent = fixed(s.velocity, 1);
  $("tool").textContent = s.tool;
  $("tool-offset").textContent = s.tool_offset && s.tool_offset.some((v) => v) ?
    `offset ${s.tool_offset.map((v) => fixed(v)).join(" ")}` : "";
  const direction = { 1: "fwd", "-1": "rev", 0: "stopped" }[s.spindle_direction] ?? "";
  $("spindle-state").textContent = `${direction} ${fixed(s.spindle_speed, 0)} rpm`;
  $("flood").classList.toggle("on", s.is_flood);
  $("mist").classList.toggle("on", s.is_mist);
  showOverride("feedrate", s.feedrate);
  showOverride("rapidrate", s.rapidrate);
  showOverride("spindle-override", s.spindle_override);
  $("optional-stop").checked = s.is_optional_stop;
  $("block-delete").checked = s.is_block_delete;
  if (s.file !== programFile) {
    loadProgram(s.file);
    if (isPreviewShown) loadPreview();
  }
  highlightLine(executingLine(s));
  draw();
}

function showOverride(id, value) {
  const slider = $(id);
  if (document.activeElement === slider || value === null) return;  // the operator moves it
  slider.value = value;
  $(`${id}-value`).textContent = `${Math.round(value)}%`;
}

// ------------------------------------------------------------------ MDI
function showHistory(lines) {
  $("mdi-history").replaceChildren(...lines.slice(-50).reverse().map((line) => {
    const item = document.createElement("li");
    item.textContent = line;
    item.onclick = () => { $("mdi-text").value = line; $("mdi-text").focus(); };
    item.ondblclick = () => send("mdi", { text: line });
    return item;
  }));
}

$("mdi-form").onsubmit = (event) => {
  event.preventDefault();
  const text = $("mdi-text").value.trim();
  if (!text) return;
  send("mdi", { text }).then((result) => { if (result.status === "DONE") $("mdi-text").value = ""; });
};

// ------------------------------------------------------------------ program
async function loadFiles() {
  const answer = await (await fetch(withToken("/api/files"))).json();
  $("program-list").replaceChildren(...answer.files.map((name) => new Option(name, name)));
}

async function loadProgram(file) {
  programFile = file;
  $("program-file").textContent = file || "";
  const answer = await (await fetch(withToken("/api/program"))).json();
  $("listing").replaceChildren(...answer.lines.map((line) => {
    const item = document.createElement("li");
    item.textContent = line || " ";
    return item;
  }));
  highlightLine(executingLine(status));
}

// The line being cut, as AXIS shows it: motion's (current_line runs ahead, with readahead).
function executingLine(s) {
  return s.motion_line || s.current_line || 0;
}

let highlighted = 0;
function highlightLine(line) {
  const items = $("listing").children;
  if (highlighted && items[highlighted - 1]) items[highlighted - 1].classList.remove("current");
  highlighted = line;
  const item = items[line - 1];
  if (item) {
    item.classList.add("current");
    item.scrollIntoView({ block: "center" });
  }
}

$("program-open").onclick = () => {
  const file = $("program-list").value;
  if (file) send("open", { file });
};
$("program-refresh").onclick = loadFiles;
$("run").onclick = () => {  // "from line": a whole line number, or empty for the start
  const text = $("run-line").value.trim();
  if (text && !/^[0-9]+$/.test(text)) notice("error", `'${text}' is not a line number`);
  else send("run", { line: text ? Number(text) : 0 });
};
$("pause").onclick = () => send("pause");
$("resume").onclick = () => send("resume");
$("step").onclick = () => send("step");
$("stop").onclick = () => send("abort");
$("optional-stop").onchange = (e) => send("optional_stop", { on: e.target.checked });
$("block-delete").onchange = (e) => send("block_delete", { on: e.target.checked });

// ------------------------------------------------------------------ machine
$("estop").onclick = () => send("estop", { on: !status.is_estop });
$("power").onclick = () => send("machine", { on: status.task_state !== "ON" });
$("abort").onclick = () => { stopAllJogs(); send("abort"); };
$("home-all").onclick = () => send("home", { joint: -1 });
$("unhome-all").onclick = () => send("unhome", { joint: -1 });
$("override-limits").onclick = () => send("override_limits");
$("flood").onclick = () => send("flood", { on: !status.is_flood });
$("mist").onclick = () => send("mist", { on: !status.is_mist });
// Fwd and Rev start the spindle at the rpm typed (DEFAULT_SPINDLE_0_SPEED at first).
function spindle(action) {
  const speed = parseDecimal($("spindle-speed").value);
  if (speed === null) notice("error", `'${$("spindle-speed").value}' is not an rpm`);
  else send("spindle", { action, speed });
}
document.querySelectorAll("[data-spindle]").forEach((button) => {
  const action = button.dataset.spindle;
  button.onclick = () => (["forward", "reverse"].includes(action) ?
    spindle(action) : send("spindle", { action }));
});

// Keyboard like AXIS: arrows jog X and Y, PgUp/PgDn Z, Esc stops everything, F1 E-stop,
// F2 machine on/off, F7 mist, F8 flood, F9 spindle forward, F10 reverse, F11 slower,
// F12 faster. Jog keys not while typing in a field.
const FUNCTION_KEYS = {
  F1: () => $("estop").click(),
  F2: () => $("power").click(),
  F7: () => $("mist").click(),
  F8: () => $("flood").click(),
  F9: () => spindle("forward"),
  F10: () => spindle("reverse"),
  F11: () => send("spindle", { action: "slower" }),
  F12: () => send("spindle", { action: "faster" }),
};
const JOG_KEYS = {
  ArrowLeft: ["X", -1], ArrowRight: ["X", 1], ArrowDown: ["Y", -1], ArrowUp: ["Y", 1],
  PageDown: ["Z", -1], PageUp: ["Z", 1],
};
document.addEventListener("keydown", (event) => {
  if (event.key === "Escape") { stopAllJogs(); send("abort"); return; }
  if (FUNCTION_KEYS[event.key]) { event.preventDefault(); FUNCTION_KEYS[event.key](); return; }
  const typing = ["INPUT", "SELECT", "TEXTAREA"].includes(document.activeElement.tagName)
    && document.activeElement.type !== "range" && document.activeElement.type !== "checkbox";
  const jog = JOG_KEYS[event.key];
  if (!jog || typing || !config || !config.axes.includes(jog[0])) return;
  event.preventDefault();
  if (!event.repeat) jogStart(jog[0], jog[1]);
});
document.addEventListener("keyup", (event) => {
  const jog = JOG_KEYS[event.key];
  if (jog) jogStop(jog[0]);
});
// A page that loses focus stops its jogs (a released key would never arrive).
window.addEventListener("blur", stopAllJogs);
document.addEventListener("visibilitychange", () => { if (document.hidden) stopAllJogs(); });

connect();

// ------------------------------------------------------------------ toolpath preview
// The server runs the open program through its own preview interpreter (/api/preview):
// points [x, y, z, kind (0 rapid, 1 feed), line] in work coordinates. Drawn as an
// orthographic view: drag rotates, shift+drag or two fingers pan, the wheel zooms.
// [yaw about Z, pitch about the screen's x, roll in the screen plane]
const VIEWS = {
  top: [0, 0, 0], front: [0, -Math.PI / 2, 0], side: [-Math.PI / 2, -Math.PI / 2, 0],
  iso: [-Math.PI / 4, -0.96, 0], lathe: [Math.PI, -Math.PI / 2, -Math.PI / 2],  // Z right, X up
};
const view = { yaw: VIEWS.iso[0], pitch: VIEWS.iso[1], roll: 0, scale: 1, x: 0, y: 0 };
let toolpath = { points: [], error: null };
let isPreviewShown = false;
let isDrawPending = false;

// The program panel's tabs: the listing, the preview, the tool table.
function showTab(name) {
  isPreviewShown = name === "preview";
  $("listing").hidden = name !== "listing";
  $("preview-box").hidden = name !== "preview";
  $("preview-views").hidden = name !== "preview";
  $("tools-box").hidden = name !== "tools";
  for (const tab of ["listing", "preview", "tools"]) {
    $(`show-${tab}`).classList.toggle("on", tab === name);
  }
  if (name === "preview") loadPreview();
  if (name === "tools") loadTools();
}
$("show-listing").onclick = () => showTab("listing");
$("show-preview").onclick = () => showTab("preview");
$("show-tools").onclick = () => showTab("tools");

async function loadPreview() {
  toolpath = await (await fetch(withToken("/api/preview"))).json();
  $("preview").dataset.points = toolpath.points.length;  // for tests and curious operators
  const error = toolpath.error;
  $("preview-error").textContent = error ? `line ${error.line}: ${error.message}` :
    toolpath.is_truncated ? "program too long: preview cut short" : "";
  fit();
}

function project(x, y, z) {
  const cy = Math.cos(view.yaw), sy = Math.sin(view.yaw);
  const cp = Math.cos(view.pitch), sp = Math.sin(view.pitch);
  const x1 = x * cy - y * sy, y1 = x * sy + y * cy;
  const y2 = y1 * cp - z * sp;
  const cr = Math.cos(view.roll), sr = Math.sin(view.roll);
  return [x1 * cr - y2 * sr, x1 * sr + y2 * cr];
}

function limitsBox() {
  // The machine limits, shifted into work coordinates by the current offset.
  const limits = (config && config.limits) || {};
  const axes = status.axes || "";
  const box = [];
  for (const letter of "XYZ") {
    const index = axes.indexOf(letter);
    const shift = index >= 0 && status.work[index] !== null && status.machine[index] !== null ?
      status.work[index] - status.machine[index] : 0;
    const range = limits[letter];
    if (!range) return null;
    box.push([range[0] + shift, range[1] + shift]);
  }
  return box;
}

function fit() {
  const canvas = $("preview");
  let minX = Infinity, maxX = -Infinity, minY = Infinity, maxY = -Infinity;
  for (const [x, y, z] of [[0, 0, 0], ...toolpath.points]) {  // moves start at the origin
    const [sx, sy] = project(x, y, z);
    minX = Math.min(minX, sx); maxX = Math.max(maxX, sx);
    minY = Math.min(minY, sy); maxY = Math.max(maxY, sy);
  }
  if (!Number.isFinite(minX)) { minX = minY = -10; maxX = maxY = 10; }
  const width = canvas.clientWidth || 400, height = canvas.clientHeight || 300;
  view.scale = 0.85 * Math.min(width / Math.max(maxX - minX, 1e-3), height / Math.max(maxY - minY, 1e-3));
  view.x = -(minX + maxX) / 2;
  view.y = -(minY + maxY) / 2;
  draw();
}

function draw() {
  if (!isPreviewShown || isDrawPending) return;
  isDrawPending = true;
  requestAnimationFrame(() => { isDrawPending = false; paint(); });
}

function paint() {
  const canvas = $("preview");
  const ratio = window.devicePixelRatio || 1;
  canvas.width = canvas.clientWidth * ratio;
  canvas.height = canvas.clientHeight * ratio;
  const g = canvas.getContext("2d");
  const toScreen = (x, y, z) => {
    const [px, py] = project(x, y, z);
    return [(px + view.x) * view.scale, -(py + view.y) * view.scale];
  };
  g.setTransform(ratio, 0, 0, ratio, 0, 0);
  g.translate(canvas.clientWidth / 2, canvas.clientHeight / 2);
  const box = limitsBox();
  if (box) {  // the 12 edges of the limits box
    g.strokeStyle = "#5a4a2a"; g.lineWidth = 1; g.setLineDash([]);
    g.beginPath();
    for (let edge = 0; edge < 12; edge++) {
      const axis = Math.floor(edge / 4), corner = edge % 4;
      const a = [0, 0, 0], b = [0, 0, 0];
      const others = [0, 1, 2].filter((n) => n !== axis);
      a[others[0]] = b[others[0]] = box[others[0]][corner & 1];
      a[others[1]] = b[others[1]] = box[others[1]][corner >> 1];
      a[axis] = box[axis][0]; b[axis] = box[axis][1];
      g.moveTo(...toScreen(...a)); g.lineTo(...toScreen(...b));
    }
    g.stroke();
  }
  const current = executingLine(status);
  const isRunning = status.interp_state && status.interp_state !== "IDLE";
  let previous = [0, 0, 0];
  // Three passes, one per look: rapids (dashed), feeds to come, feeds already cut.
  const looks = [
    [(kind) => kind === 0, "#3aa0b8", [4, 4]],
    [(kind, line) => kind === 1 && !(isRunning && line < current), "#e6e9ee", []],
    [(kind, line) => kind === 1 && isRunning && line < current, "#3fb950", []],
  ];
  for (const [wanted, color, dash] of looks) {
    g.strokeStyle = color; g.setLineDash(dash); g.lineWidth = 1.2;
    g.beginPath();
    previous = [0, 0, 0];
    for (const [x, y, z, kind, line] of toolpath.points) {
      if (wanted(kind, line)) { g.moveTo(...toScreen(...previous)); g.lineTo(...toScreen(x, y, z)); }
      previous = [x, y, z];
    }
    g.stroke();
  }
  const axes = status.axes || "";
  const at = [..."XYZ"].map((letter) => axes.includes(letter) ? status.work[axes.indexOf(letter)] || 0 : 0);
  const [tx, ty] = toScreen(...at);  // the tool
  g.setLineDash([]); g.strokeStyle = "#f85149"; g.lineWidth = 2;
  g.beginPath(); g.arc(tx, ty, 6, 0, 2 * Math.PI);
  g.moveTo(tx - 10, ty); g.lineTo(tx + 10, ty); g.moveTo(tx, ty - 10); g.lineTo(tx, ty + 10);
  g.stroke();
}

document.querySelectorAll("[data-view]").forEach((button) => {
  button.onclick = () => {
    const chosen = VIEWS[button.dataset.view];
    if (chosen) [view.yaw, view.pitch, view.roll] = chosen;
    fit();
  };
});

(() => {  // rotate, pan and zoom with mouse or fingers
  const canvas = $("preview");
  const pointers = new Map();
  canvas.onpointerdown = (event) => {
    canvas.setPointerCapture(event.pointerId);
    pointers.set(event.pointerId, [event.clientX, event.clientY]);
  };
  canvas.onpointermove = (event) => {
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
    draw();
  };
  const release = (event) => pointers.delete(event.pointerId);
  canvas.onpointerup = release;
  canvas.onpointercancel = release;
  canvas.onwheel = (event) => {
    event.preventDefault();
    view.scale *= event.deltaY < 0 ? 1.15 : 1 / 1.15;
    draw();
  };
})();
window.addEventListener("resize", draw);

// ------------------------------------------------------------------ tool table, upload
async function loadTools() {
  const answer = await (await fetch(withToken("/api/tools"))).json();
  $("tools").tBodies[0].replaceChildren(...answer.tools.map((entry) => {
    const row = document.createElement("tr");
    row.dataset.tool = entry.tool;
    row.classList.toggle("in-spindle", entry.tool === status.tool);
    const cells = [`T${entry.tool}`, fixed(entry.z), fixed(entry.x), fixed(entry.diameter), entry.comment, ""];
    for (const text of cells) row.insertCell().textContent = text;
    row.cells[2].className = "lathe-only";
    row.cells[4].className = "comment";
    const edit = Object.assign(document.createElement("button"), { textContent: "Edit" });
    edit.onclick = () => editTool(row, entry);
    row.cells[5].append(edit);
    return row;
  }));
}

// A tool row becomes a small form: numbers take ',' or '.' (GUI-003); Save sends tool_set,
// which rewrites the tool table file and has iocontrol reload it.
function editTool(row, entry) {
  const field = (cell, value, name, isNumber = true) => {
    const input = Object.assign(document.createElement("input"), { value, name });
    if (isNumber) { input.inputMode = "decimal"; input.className = "number"; }
    row.cells[cell].replaceChildren(input);
    return input;
  };
  const z = field(1, fixed(entry.z), "z");
  const x = field(2, fixed(entry.x), "x");
  const diameter = field(3, fixed(entry.diameter), "diameter");
  const comment = field(4, entry.comment, "comment", false);
  const save = Object.assign(document.createElement("button"), { textContent: "Save" });
  const cancel = Object.assign(document.createElement("button"), { textContent: "Cancel" });
  cancel.onclick = loadTools;
  save.onclick = async () => {
    const values = {};
    for (const [name, input] of Object.entries({ z, diameter, ...(config.is_lathe ? { x } : {}) })) {
      values[name] = parseDecimal(input.value);
      if (values[name] === null) { notice("error", `${name}: '${input.value}' is not a number`); return; }
    }
    const result = await send("tool_set", { tool: entry.tool, ...values, comment: comment.value });
    if (result.status === "DONE") loadTools();
  };
  row.cells[5].replaceChildren(save, cancel);
  row.onkeydown = (event) => { if (event.key === "Enter") save.click(); };
  z.focus();
}

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
  $("program-list").value = answer.file;
  send("open", { file: answer.file });
};
