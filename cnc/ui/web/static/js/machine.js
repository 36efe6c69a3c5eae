// The machine: E-stop, STOP, power, the state in words, DRO, jogging, spindle, coolant,
// overrides, MDI and the keyboard.
//
// Stops come first: STOP and E-STOP act on pointerdown (the earliest event a press gives)
// and Esc on keydown, caught before any other handler; each sends its command at once,
// in that event handler. Nothing the page draws runs long enough to delay them: the
// listing draws only the lines in view, the preview draws on the graphics card, and the
// heavy lifting (reading a program, its toolpath) is done by a worker thread.

import {
  $, el, emit, fixed, fromShown, isTyping, length, on, parseDecimal, setShownUnits, setText,
  shownUnits, state, toShown,
} from "./core.js";
import { connect, send, sendQuietly } from "./link.js";
import { askNumber, closeModal } from "./modal.js";
import { notice } from "./notices.js";

const SYSTEMS = ["G54", "G55", "G56", "G57", "G58", "G59", "G59.1", "G59.2", "G59.3"];

// ------------------------------------------------------------------ stops
function stopEverything() {
  stopAllJogs();
  send("abort");
}

let isEstopPress = false;  // this press set the E-stop: its click must not reset it
$("estop").addEventListener("pointerdown", () => {
  isEstopPress = !state.status.is_estop;
  if (isEstopPress) send("estop", { on: true });
});
$("estop").addEventListener("click", () => {
  if (isEstopPress) { isEstopPress = false; return; }
  // a click without a press of its own is the keyboard (Enter, Space): same as F1
  send("estop", { on: !state.status.is_estop });
});

let isAbortPress = false;
$("abort").addEventListener("pointerdown", () => { isAbortPress = true; stopEverything(); });
$("abort").addEventListener("click", () => {
  if (!isAbortPress) stopEverything();  // the keyboard: Enter or Space on STOP
  isAbortPress = false;
});

window.addEventListener("keydown", (event) => {
  if (event.key === "Escape") {
    stopEverything();  // always, wherever the focus is, as AXIS
    closeModal();
    event.preventDefault();
    event.stopImmediatePropagation();
  } else if (event.key === "F1") {
    event.preventDefault();
    send("estop", { on: !state.status.is_estop });
  }
}, { capture: true });

// ------------------------------------------------------------------ state in words
// What the machine does, in the words an operator uses (never READING/WAITING).
export function machineState(s) {
  if (!state.isSocketOpen) return ["OFFLINE", "the server does not answer", "offline"];
  if (!s.is_connected) return ["OFFLINE", "the controller is not running", "offline"];
  if (s.is_estop) return ["E-STOP", "reset E-STOP to continue", "estop"];
  if (s.task_state !== "ON") return ["MACHINE OFF", "press Machine to switch it on", "off"];
  if (s.homing && s.homing.some(Boolean)) return ["HOMING", "", "busy"];
  const isIdle = s.interp_state === "IDLE";
  if (s.task_mode === "AUTO" && !isIdle) {
    const line = executingLine(s);
    if (s.is_program_stop) {  // the program paused itself: M0, M1, or the end of a step
      return ["STOPPED", `at line ${s.current_line} (M0, M1 or a step): Resume to continue`, "paused"];
    }
    if (s.is_paused) return ["PAUSED", `at line ${line}: Resume to continue`, "paused"];
    return ["RUNNING", `line ${line}`, "running"];
  }
  if (s.task_mode === "MDI" && !isIdle) return ["MDI", "running an MDI command", "running"];
  if (!s.is_all_homed) return ["NOT HOMED", "home the machine before running programs", "off"];
  return ["READY", s.task_mode === "MANUAL" ? "manual" : s.task_mode.toLowerCase(), "ready"];
}

// The line to highlight: motion's (the interpreter reads ahead), except where the program
// paused itself (M0, M1, a step's end): motion is at rest and that line is the one reached.
export function executingLine(s) {
  if (s.is_program_stop) return s.current_line || 0;
  return s.motion_line || s.current_line || 0;
}

function showState() {
  const s = state.status;
  const [word, detail, kind] = machineState(s);
  setText($("state"), word);
  $("state").dataset.kind = kind;
  setText($("state-detail"), detail);
  $("state-detail").title = detail;
  const isOffline = kind === "offline";
  document.body.classList.toggle("offline", isOffline);
  $("offline-why").textContent = state.isSocketOpen ?
    "The controller is not running." : "The web server does not answer.";
  document.body.classList.toggle("is-estop", !isOffline && Boolean(s.is_estop));
  $("estop-banner").hidden = isOffline || !s.is_estop;
  setText($("estop"), !isOffline && s.is_estop ? "E-STOP ACTIVE" : "E-STOP");
  $("estop").title = s.is_estop ? "E-stop is active: press to reset (F1)" : "E-stop (F1)";
  $("power").classList.toggle("on", !isOffline && s.task_state === "ON");
  setText($("power"), !isOffline && s.task_state === "ON" ? "Machine ON" : "Machine OFF");
}

// ------------------------------------------------------------------ DRO
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
      "<td><button class=touch title='Set the work position here (G10 L20)'>Touch</button></td>";
    row.querySelector(".home").onclick = () => send("home", { joint });
    const touch = row.querySelector(".touch");
    touch.hidden = kind === "joints";
    touch.onclick = () => touchOff(label);
  });
}

export async function touchOff(axis, system = null) {
  const active = system || state.status.g5x || "G54";
  const value = await askNumber(`Touch off ${axis} (${active})`,
    `${axis} here reads (${shownUnits()})`, "0");
  if (value !== null) send("touch_off", { axis, value: fromShown(value), system: active });
}

function showDro(s) {
  const axes = [...(s.axes || "")];
  const homed = s.homed || [];
  const isJoints = isJointViewChosen || (!s.is_all_homed && homed.length !== axes.length);
  const labels = isJoints ? homed.map((_, index) => `J${index}`) : axes;
  const kind = isJoints ? "joints" : "axes";
  const rows = $("dro").tBodies[0].rows;
  if (kind !== droKind || rows.length !== labels.length) buildDro(labels, kind);
  $("dro-joints").classList.toggle("on", isJoints);
  labels.forEach((_, index) => {
    const row = rows[index];
    const cells = row.cells;
    setText(cells[1], length(isJoints ? s.joint_position[index] : s.work[index]));
    setText(cells[2], isJoints ? "" : length(s.machine[index]));
    setText(cells[3], isJoints ? "" : length(s.dtg[index]));
    row.classList.toggle("is-homed", Boolean(homed[index]));
    row.classList.toggle("is-homing", Boolean(s.homing && s.homing[index]));
  });
}

$("dro-joints").onclick = () => { isJointViewChosen = !isJointViewChosen; showDro(state.status); };
$("units").onclick = () => setShownUnits(shownUnits() === "mm" ? "inch" : "mm");
on("units", () => {
  $("units").textContent = shownUnits() === "inch" ? "in" : "mm";
  showDro(state.status);
  setJogChoices();
  showMachineNow(state.status);
});

// ------------------------------------------------------------------ machine vs program
// The machine's spindle, coolant and tool velocity now, beside the interpreter's modal
// state (read ahead: M5 M9 F0 there while the machine still cuts), as LinuxCNC's screens
// tell them apart.
function showMachineNow(s) {
  const direction = { 1: "FWD", "-1": "REV" }[s.spindle_direction];
  setText($("now-spindle"), direction ? `S ${fixed(s.spindle_speed, 0)} rpm ${direction}` : "spindle off");
  const coolant = [s.is_flood ? "flood" : null, s.is_mist ? "mist" : null].filter(Boolean);
  setText($("now-coolant"), coolant.length ? `${coolant.join(" + ")} on` : "coolant off");
  const units = shownUnits() === "inch" ? "in/min" : "mm/min";
  setText($("now-velocity"), `${fixed(toShown(s.velocity), shownUnits() === "inch" ? 2 : 0)} ${units}`);
  setText($("now-tool"), `T${s.tool ?? "—"}`);
  setText($("spindle-state"), direction ? `${direction} ${fixed(s.spindle_speed, 0)} rpm` : "OFF");
  $("spindle-state").classList.toggle("on", Boolean(direction));
  setText($("gcodes"), s.gcodes || "—");
  setText($("mcodes"), s.mcodes || "");
  setText($("modal-fs"), `F${fixed(s.feed, 1)} S${fixed(s.speed, 0)}`);
}


// ------------------------------------------------------------------ jogging
// A step chosen as buttons (not a <select>, whose arrow keys would change the step instead
// of jogging); a continuous jog is held by re-sending "hold" while the key or button is
// down (the server stops a jog that is not held: see hub.py).
let step = 0, angularStep = 0;
const jogging = new Map();  // axis -> hold timer of a continuous jog

function setJogChoices() {
  const config = state.config;
  if (!config) return;
  segments("increment", config.increments, () => step, (value) => { step = value; });
  segments("angular-increment", config.angular_increments, () => angularStep, (value) => { angularStep = value; });
  speedSlider("jog-speed", config.jog_speed, true);
  speedSlider("angular-speed", config.angular_jog_speed, false);
}

function segments(id, choices, get, set) {
  $(id).replaceChildren(...choices.map((choice) => {
    const label = choice.distance ? choice.label : "Cont.";
    const button = el("button", { textContent: label, title: choice.label, role: "radio" });
    button.dataset.distance = choice.distance;
    button.onclick = () => {
      set(choice.distance);
      for (const other of $(id).children) other.classList.toggle("on", other === button);
      button.blur();  // keys go on jogging
    };
    button.classList.toggle("on", choice.distance === get());
    return button;
  }));
}

function speedSlider(id, range, isLinear) {
  const slider = $(id);
  slider.min = range.min; slider.max = range.max;
  slider.step = Math.max((range.max - range.min) / 200, 0.001);
  if (!slider.dataset.set) { slider.value = range.default; slider.dataset.set = "1"; }
  slider.oninput = () => {
    const value = Number(slider.value);
    $(`${id}-value`).textContent = isLinear ?
      `${fixed(toShown(value), shownUnits() === "inch" ? 1 : 0)} ${shownUnits() === "inch" ? "in" : "mm"}/min` :
      `${fixed(value, 0)} °/min`;
  };
  slider.oninput();
}

function buildJog(axes) {
  $("jog-buttons").replaceChildren(...[...axes].flatMap((letter) => [-1, 1].map((direction) => {
    const button = el("button", { className: "jog", textContent: `${letter}${direction < 0 ? "−" : "+"}` });
    button.dataset.axis = letter;
    button.onpointerdown = (event) => { button.setPointerCapture(event.pointerId); jogStart(letter, direction); };
    for (const end of ["pointerup", "pointercancel", "lostpointercapture"]) {
      button.addEventListener(end, () => jogStop(letter));
    }
    return button;
  })));
}

export function jogStart(axis, direction) {
  if (!state.status.is_connected) return;
  const isAngular = "ABC".includes(axis);
  const speed = Number($(isAngular ? "angular-speed" : "jog-speed").value);
  const distance = isAngular ? angularStep : step;
  if (distance > 0) {
    send("jog", { action: "increment", axis, direction, speed, distance });
  } else if (!jogging.has(axis)) {
    const hold = setInterval(() => sendQuietly("jog", { action: "hold", axis }),
      (state.config.jog_hold_s || 0.1) * 1000);
    jogging.set(axis, hold);
    send("jog", { action: "start", axis, direction, speed });
  }
}

export function jogStop(axis) {
  if (!jogging.has(axis)) return;
  clearInterval(jogging.get(axis));
  jogging.delete(axis);
  send("jog", { action: "stop", axis });
}

export function stopAllJogs() { [...jogging.keys()].forEach(jogStop); }

// A page that loses focus stops its jogs (a released key would never arrive).
window.addEventListener("blur", stopAllJogs);
document.addEventListener("visibilitychange", () => { if (document.hidden) stopAllJogs(); });
on("link", (isUp) => { if (!isUp) { jogging.forEach(clearInterval); jogging.clear(); } });

// ------------------------------------------------------------------ spindle, coolant
function spindleLimits() { return state.config.spindle; }

function spindle(action) {
  if (action !== "forward" && action !== "reverse") { send("spindle", { action }); return; }
  const text = $("spindle-speed").value;
  const speed = parseDecimal(text);
  const limits = spindleLimits();
  const top = action === "reverse" ? limits.max_reverse : limits.max;
  if (speed === null) notice("error", `'${text}' is not an rpm`);
  else if (speed > top) notice("error", `${speed} rpm is above the spindle's maximum, ${top} rpm`);
  else if (speed < limits.min) notice("error", `${speed} rpm is below the spindle's minimum, ${limits.min} rpm`);
  else send("spindle", { action, speed });
}
document.querySelectorAll("[data-spindle]").forEach((button) => {
  button.onclick = () => spindle(button.dataset.spindle);
});
$("flood").onclick = () => send("flood", { on: !state.status.is_flood });
$("mist").onclick = () => send("mist", { on: !state.status.is_mist });

// ------------------------------------------------------------------ overrides
const overrideTimers = {};  // slider id -> the send waiting for the slider to rest
function setRange(id, min, max) {
  const slider = $(id);
  slider.min = min; slider.max = max;
  slider.oninput = () => {
    $(`${id}-value`).textContent = `${slider.value}%`;
    clearTimeout(overrideTimers[id]);  // sent once the slider rests for a moment
    overrideTimers[id] = setTimeout(
      () => send(id.replace("-", "_"), { percent: Number(slider.value) }), 120);
  };
}
document.querySelectorAll("[data-reset]").forEach((button) => {
  const id = button.dataset.reset;
  button.onclick = () => {
    clearTimeout(overrideTimers[id]);  // a drag's value still to be sent must not undo it
    // shown at once: if the drag's value was never sent, no status change will show it
    $(id).value = 100;
    $(`${id}-value`).textContent = "100%";
    send(id.replace("-", "_"), { percent: 100 });
  };
});

function showOverride(id, value) {
  const slider = $(id);
  if (document.activeElement === slider || value === null || value === undefined) return;
  if (Number(slider.value) !== value) slider.value = value;
  setText($(`${id}-value`), `${Math.round(value)}%`);
}

// ------------------------------------------------------------------ MDI
function showHistory(lines) {
  $("mdi-history").replaceChildren(...lines.slice(-50).reverse().map((line) => el("li", {
    textContent: line,
    onclick: () => { $("mdi-text").value = line; $("mdi-text").focus(); },
    ondblclick: () => send("mdi", { text: line }),
  })));
}

$("mdi-form").onsubmit = (event) => {
  event.preventDefault();
  const text = $("mdi-text").value.trim();
  if (!text) return;
  send("mdi", { text }).then((result) => { if (result.status === "DONE") $("mdi-text").value = ""; });
};

// ------------------------------------------------------------------ coordinate system
$("g5x").replaceChildren(...SYSTEMS.map((name) => new Option(name, name)));
$("g5x").onchange = () => {
  send("select_system", { system: $("g5x").value });
  $("g5x").blur();
};

// ------------------------------------------------------------------ keyboard
// As AXIS: arrows jog X and Y (a lathe: Z and X), PgUp/PgDn Z, Esc stops, F1 E-stop,
// F2 machine on/off, F7 mist, F8 flood, F9/F10 spindle forward/reverse, F11/F12 slower and
// faster, I next step, Ctrl+Home home all; R run, P pause, S resume, T step; ? this sheet.
// Not while typing in a field.
export const JOG_KEYS = {
  ArrowLeft: ["X", -1], ArrowRight: ["X", 1], ArrowDown: ["Y", -1], ArrowUp: ["Y", 1],
  PageDown: ["Z", -1], PageUp: ["Z", 1],
};
const FUNCTION_KEYS = {
  F2: () => send("machine", { on: state.status.task_state !== "ON" }),
  F7: () => $("mist").click(),
  F8: () => $("flood").click(),
  F9: () => spindle("forward"),
  F10: () => spindle("reverse"),
  F11: () => spindle("slower"),
  F12: () => spindle("faster"),
};
const LETTER_KEYS = {
  r: () => $("run").click(), p: () => $("pause").click(), s: () => $("resume").click(),
  t: () => $("step").click(), i: () => nextStep(1), I: () => nextStep(-1),
  "?": () => emit("help"),
};

function nextStep(direction) {
  const buttons = [...$("increment").children];
  const index = buttons.findIndex((button) => button.classList.contains("on"));
  const next = buttons[(index + direction + buttons.length) % buttons.length];
  if (next) next.click();
}

document.addEventListener("keydown", (event) => {
  if (FUNCTION_KEYS[event.key]) {
    event.preventDefault();
    if (!event.repeat && state.status.is_connected) FUNCTION_KEYS[event.key]();
    return;
  }
  if (isTyping() || !$("modal").hidden) return;
  if (event.key === "Home" && event.ctrlKey) { event.preventDefault(); send("home", { joint: -1 }); return; }
  if (LETTER_KEYS[event.key] && !event.ctrlKey && !event.altKey && !event.metaKey) {
    if (!event.repeat) LETTER_KEYS[event.key]();
    return;
  }
  const jog = JOG_KEYS[event.key];
  if (!jog || !state.config || !state.config.axes.includes(jog[0])) return;
  event.preventDefault();  // also on a focused list or slider: the key jogs, nothing else
  if (!event.repeat) jogStart(jog[0], jog[1]);
});
document.addEventListener("keyup", (event) => {
  const jog = JOG_KEYS[event.key];
  if (jog) jogStop(jog[0]);
});

// ------------------------------------------------------------------ buttons
$("power").onclick = () => send("machine", { on: state.status.task_state !== "ON" });
$("home-all").onclick = () => send("home", { joint: -1 });
$("unhome-all").onclick = () => send("unhome", { joint: -1 });
$("override-limits").onclick = () => send("override_limits");

// ------------------------------------------------------------------ updates
on("config", (config) => {
  document.title = config.title || "cnc";
  document.body.classList.toggle("machine-first", !config.is_position_relative);
  document.body.classList.toggle("read-only", !config.is_control);
  document.body.classList.toggle("lathe", config.is_lathe);
  buildJog(config.axes);
  setJogChoices();
  $("angular-jog").hidden = !/[ABC]/.test(config.axes);
  const limits = config.spindle;
  if (!$("spindle-speed").value) $("spindle-speed").value = limits.default;
  $("spindle-range").textContent = `${limits.min}–${limits.max} rpm`;
  if (config.is_lathe) {
    Object.assign(JOG_KEYS, { ArrowLeft: ["Z", -1], ArrowRight: ["Z", 1], ArrowDown: ["X", 1], ArrowUp: ["X", -1] });
  }
  setRange("feedrate", 0, config.overrides.feed_max);
  setRange("rapidrate", 0, config.overrides.rapid_max);
  setRange("spindle-override", config.overrides.spindle_min, config.overrides.spindle_max);
  $("macros").replaceChildren(...config.macros.map((macro, index) => el("button", {
    textContent: macro.label, title: macro.commands, onclick: () => send("macro", { index }),
  })));
  showHistory(config.mdi_history);
  $("units").textContent = shownUnits() === "inch" ? "in" : "mm";
});

on("status", () => {
  const s = state.status;
  showState();
  if (!s.is_connected) return;
  showDro(s);
  showMachineNow(s);
  if (document.activeElement !== $("g5x")) $("g5x").value = s.g5x;
  $("flood").classList.toggle("on", Boolean(s.is_flood));
  $("mist").classList.toggle("on", Boolean(s.is_mist));
  showOverride("feedrate", s.feedrate);
  showOverride("rapidrate", s.rapidrate);
  showOverride("spindle-override", s.spindle_override);
});
on("link", showState);
on("history", (message) => showHistory(message.lines));

export function start() { connect(); }
