// The other views: work offsets, tool table, probing, the G-code editor, the job history;
// the keyboard sheet, the theme, and the [DISPLAY] message dialogs.

import {
  $, duration, el, emit, fetchJson, fixed, fromShown, length, on, parseDecimal, shownUnits, state,
} from "./core.js";
import { send } from "./link.js";
import { touchOff } from "./machine.js";
import { askNumber, showModal } from "./modal.js";
import { notice } from "./notices.js";

const SYSTEMS = ["G54", "G55", "G56", "G57", "G58", "G59", "G59.1", "G59.2", "G59.3"];
const loaders = {};  // view -> what to do when it is shown

// ------------------------------------------------------------------ switching views
export function showView(name) {
  for (const view of document.querySelectorAll("main > .view")) view.hidden = view.id !== `view-${name}`;
  for (const button of $("views").children) button.classList.toggle("on", button.dataset.view === name);
  document.body.dataset.view = name;
  if (loaders[name]) loaders[name]();
}
for (const button of $("views").children) button.onclick = () => showView(button.dataset.view);

// ------------------------------------------------------------------ offsets
async function loadOffsets() {
  let table;
  try {
    table = await fetchJson("/api/offsets");
  } catch (error) {
    notice("error", `offsets: ${error.message}`);
    return;
  }
  const axes = [...table.axes];
  $("offsets").tHead.replaceChildren(el("tr", {},
    el("th", { textContent: "System" }), ...axes.map((a) => el("th", { textContent: `${a} (${shownUnits()})` })),
    el("th", { textContent: "XY rotation (°)" }), el("th")));
  const rows = table.systems.map((system) => {
    const isActive = system.name === table.active;
    const row = el("tr", { className: isActive ? "active" : "" }, el("th", { textContent: system.name + (isActive ? " ●" : "") }));
    row.dataset.system = system.name;
    system.values.forEach((value, index) => row.append(valueCell(system.name, axes[index], value)));
    row.append(rotationCell(system.name, system.rotation));
    row.append(el("td", {},
      el("button", { textContent: "Use", disabled: isActive, onclick: () => changed(send("select_system", { system: system.name })) }),
      el("button", { textContent: "Clear", onclick: () => clearSystem(system.name) })));
    return row;
  });
  const g92 = el("tr", {}, el("th", { textContent: "G92" }),
    ...table.g92.map((value) => el("td", { className: "number", textContent: length(value) })),
    el("td"), el("td", {}, el("button", { textContent: "Clear", onclick: () => clearSystem("G92") })));
  $("offsets").tBodies[0].replaceChildren(...rows, g92);
  $("touch-system").replaceChildren(...SYSTEMS.map((name) => new Option(name, name)));
  $("touch-system").value = table.active || "G54";
  $("touch-axes").replaceChildren(...axes.map((axis) => el("button", {
    textContent: `Touch off ${axis}`, onclick: () => touchOff(axis, $("touch-system").value).then(reloadSoon),
  })));
}
loaders.offsets = loadOffsets;

function reloadSoon() { setTimeout(loadOffsets, 300); }
async function changed(promise) { await promise; loadOffsets(); }

function valueCell(system, axis, value) {
  return el("td", { className: "number editable", textContent: length(value), title: "Click to set (G10 L2)",
    onclick: async () => {
      const typed = await askNumber(`${system} ${axis} offset`, `offset (${shownUnits()})`, fixed(value === null ? 0 : value));
      if (typed !== null) changed(send("offset_set", { system, axis, value: fromShown(typed) }));
    } });
}

function rotationCell(system, rotation) {
  return el("td", { className: "number editable", textContent: fixed(rotation, 3), title: "Click to set (G10 L2 R)",
    onclick: async () => {
      const typed = await askNumber(`${system} XY rotation`, "degrees", fixed(rotation, 3));
      if (typed !== null) changed(send("offset_set", { system, rotation: typed }));
    } });
}

async function clearSystem(system) {
  const answer = await showModal(`Clear ${system}?`, [el("p", { textContent: `Every offset of ${system} becomes 0.` })],
    [["Clear", true], ["Cancel", null]]);
  if (answer) changed(send("offset_clear", { system }));
}

// ------------------------------------------------------------------ tools
async function loadTools() {
  let answer;
  try {
    answer = await fetchJson("/api/tools");
  } catch (error) {
    notice("error", `tools: ${error.message}`);
    return;
  }
  $("tools").tBodies[0].replaceChildren(...answer.tools.map((entry) => {
    const row = el("tr", { className: entry.tool === state.status.tool ? "in-spindle" : "" });
    row.dataset.tool = entry.tool;
    const cells = [`T${entry.tool}`, length(entry.z), length(entry.x), length(entry.diameter), entry.comment];
    cells.forEach((text) => row.append(el("td", { textContent: text })));
    row.cells[2].className = "lathe-only";
    row.cells[4].className = "comment";
    row.append(el("td", { className: "actions" },
      el("button", { textContent: "Edit", onclick: () => editTool(row, entry) }),
      el("button", { textContent: "Delete", onclick: () => deleteTool(entry.tool) })));
    return row;
  }));
}
loaders.tools = loadTools;

// A tool row becomes a small form: numbers take ',' or '.' (GUI-003); Save sends tool_set,
// which rewrites the tool table file and has iocontrol reload it.
function editTool(row, entry) {
  const field = (cell, value, name, isNumber = true) => {
    const input = el("input", { value, name, className: isNumber ? "number" : "wide" });
    if (isNumber) input.inputMode = "decimal";
    row.cells[cell].replaceChildren(input);
    return input;
  };
  const inputs = { z: field(1, fixed(entry.z), "z"), x: field(2, fixed(entry.x), "x"),
    diameter: field(3, fixed(entry.diameter), "diameter") };
  const comment = field(4, entry.comment, "comment", false);
  const save = el("button", { textContent: "Save" });
  save.onclick = async () => {
    const values = {};
    for (const [name, input] of Object.entries(inputs)) {
      if (name === "x" && !state.config.is_lathe) continue;
      values[name] = parseDecimal(input.value);
      if (values[name] === null) { notice("error", `${name}: '${input.value}' is not a number`); return; }
    }
    const result = await send("tool_set", { tool: entry.tool, ...values, comment: comment.value });
    if (result.status === "DONE") loadTools();
  };
  row.cells[5].replaceChildren(save, el("button", { textContent: "Cancel", onclick: loadTools }));
  row.onkeydown = (event) => { if (event.key === "Enter") save.click(); };
  inputs.z.focus();
}

async function deleteTool(tool) {
  const answer = await showModal(`Delete tool ${tool}?`, [el("p", { textContent: "It is removed from the tool table file." })],
    [["Delete", true], ["Cancel", null]]);
  if (answer && (await send("tool_delete", { tool })).status === "DONE") loadTools();
}

$("tool-add").onsubmit = async (event) => {
  event.preventDefault();
  const form = event.target;
  const tool = parseInt(form.tool.value, 10);
  const request = { tool, comment: form.comment.value };
  if (form.pocket.value.trim()) request.pocket = parseInt(form.pocket.value, 10);
  for (const name of ["z", "diameter"]) {
    request[name] = parseDecimal(form[name].value);
    if (request[name] === null) { notice("error", `${name}: '${form[name].value}' is not a number`); return; }
  }
  if (!(tool > 0)) { notice("error", "the tool number must be 1 or more"); return; }
  if ((await send("tool_add", request)).status === "DONE") { form.reset(); loadTools(); }
};

// ------------------------------------------------------------------ probing
const PROBES = {
  edge: { help: "Place the probe beside the edge, at the height to touch it. It probes along the axis, fast then slow.",
    fields: [["axis", "Axis", "X", ["X", "Y", "Z"]], ["direction", "Direction", "1", [["1", "+"], ["-1", "−"]]]] },
  corner: { help: "Outside corner: start diagonally off it, level with the faces; the probe steps along each face (clearance) before touching it. Inside corner: start near it, inside.",
    fields: [["x_direction", "X toward", "1", [["1", "+"], ["-1", "−"]]], ["y_direction", "Y toward", "1", [["1", "+"], ["-1", "−"]]],
      ["is_inside", "Corner", "false", [["false", "outside"], ["true", "inside"]]], ["clearance", "Clearance", 5]] },
  bore: { help: "Start inside the bore, near its centre, at the height to touch its wall. It touches X+ and X−, moves to the X centre, touches Y+ and Y−, moves to the centre, and touches X again through it.", fields: [] },
  boss: { help: "Start above the boss's centre, clear of its top. For each side it goes out, down by the depth (stopping if it touches anything), touches inwards, and comes back up and over; X, Y, then X again through the centre.",
    fields: [["boss_diameter", "Boss diameter (about)", 20], ["clearance", "Clearance", 5], ["depth", "Depth", 5]] },
  tool_length: { help: "Moves to the tool setter ([TOOLSENSOR] in the INI) and touches it with the tool in the spindle. The length is the difference to the reference tool's touch.",
    fields: [] },
};
const COMMON_FIELDS = [["search", "Search distance", 20], ["retract", "Back off", 1], ["fast_feed", "Fast feed (/min)", 200],
  ["slow_feed", "Slow feed (/min)", 20], ["tip_diameter", "Tip diameter", 0]];
let probeKind = "edge";

function buildProbeForm() {
  const spec = PROBES[probeKind];
  $("probe-help").textContent = spec.help;
  for (const button of $("probe-kinds").children) button.classList.toggle("on", button.dataset.probe === probeKind);
  const fields = probeKind === "tool_length" ? [] : [...spec.fields, ...COMMON_FIELDS];
  const saved = JSON.parse(localStorage.getItem("cnc.probe") || "{}");
  $("probe-form").replaceChildren(...fields.map(([name, label, value, choices]) => {
    const current = saved[name] ?? value;
    const input = choices ?
      el("select", { name }, ...choices.map((c) => (Array.isArray(c) ? new Option(c[1], c[0]) : new Option(c, c)))) :
      el("input", { name, value: current, inputMode: "decimal", className: "number" });
    if (choices) input.value = String(current);
    return el("label", { className: "field" }, el("span", { textContent: label }), input);
  }));
  $("probe-start").disabled = probeKind === "tool_length" && !(state.config && state.config.tool_sensor);
}
for (const button of $("probe-kinds").children) {
  button.onclick = () => { probeKind = button.dataset.probe; buildProbeForm(); };
}

function probeParams() {
  const params = {};
  const saved = JSON.parse(localStorage.getItem("cnc.probe") || "{}");
  for (const input of $("probe-form").elements) {
    const { name, value } = input;
    if (input.tagName === "SELECT") {
      params[name] = name === "is_inside" ? value === "true" : name === "axis" ? value : Number(value);
    } else {
      const number = parseDecimal(value);
      if (number === null) throw new Error(`${name}: '${value}' is not a number`);
      params[name] = fromShown(number);  // lengths, and feeds (per minute), as shown
    }
    saved[name] = value;
  }
  localStorage.setItem("cnc.probe", JSON.stringify(saved));
  return params;
}

$("probe-start").onclick = () => {
  let params;
  try { params = probeParams(); } catch (error) { notice("error", error.message); return; }
  send("probe", { kind: probeKind, params });
};
$("probe-cancel").onclick = () => send("abort");

on("probe", (probe) => {
  $("probe-steps").replaceChildren(...probe.steps.map((text, index) => {
    const done = index < probe.current || probe.state === "done" || probe.state === "confirmed";
    const kind = done ? "done" : index === probe.current ? (probe.state === "failed" ? "failed" : "running") : "";
    return el("li", { className: kind, textContent: text });
  }));
  const result = $("probe-result");
  result.hidden = !["done", "failed", "confirmed"].includes(probe.state);
  if (probe.state === "failed") {
    result.className = "probe-result bad";
    result.replaceChildren(el("b", { textContent: "Probing stopped: " }), probe.message);
  } else if (probe.state === "confirmed") {
    result.className = "probe-result";
    result.replaceChildren("Set. ", el("b", { textContent: "Confirmed." }));
  } else if (probe.state === "done") {
    result.className = "probe-result";
    result.replaceChildren(...confirmForm(probe.result));
  }
});

function confirmForm(result) {
  if (result.kind === "tool_length") {
    const tool = el("input", { value: state.status.tool || "", inputMode: "numeric", className: "number" });
    return [el("p", { textContent: `Touched the tool setter at machine Z ${length(result.touch_z)} ${shownUnits()}.` }),
      el("label", { className: "field" }, el("span", { textContent: "Tool" }), tool),
      el("div", { className: "row" },
        el("button", { textContent: "Set its length", onclick: () => send("probe_confirm", { tool: parseInt(tool.value, 10) }) }),
        el("button", { textContent: "This is the reference tool", onclick: () => send("probe_confirm", { is_reference: true }) }))];
  }
  const system = el("select", {}, ...SYSTEMS.map((name) => new Option(name, name)));
  system.value = state.status.g5x || "G54";
  const inputs = Object.entries(result.axes).map(([axis]) => [axis, el("input", { value: "0", inputMode: "decimal", className: "number" })]);
  const found = Object.entries(result.axes).map(([axis, value]) => `${axis} ${length(value)}`).join(", ");
  const words = result.diameter ? ` (diameter ${length(result.diameter)})` : "";
  return [el("p", { textContent: `Found ${result.kind} at machine ${found} ${shownUnits()}${words}.` }),
    el("div", { className: "row" }, el("label", {}, "Set in ", system),
      ...inputs.map(([axis, input]) => el("label", {}, `${axis} =`, input))),
    el("button", { className: "run", textContent: "Set offset", onclick: () => {
      const values = {};
      for (const [axis, input] of inputs) {
        const number = parseDecimal(input.value);
        if (number === null) { notice("error", `${axis}: '${input.value}' is not a number`); return; }
        values[axis] = fromShown(number);
      }
      send("probe_confirm", { system: system.value, values });
    } })];
}
loaders.probe = buildProbeForm;

// ------------------------------------------------------------------ editor
const editor = $("editor-text");
let checkTimer = null;

function showGutter(errors = []) {
  const count = editor.value.split("\n").length;
  const marks = new Map(errors.map((error) => [error.line, error.message]));
  const lines = [];
  for (let line = 1; line <= count; line++) lines.push(marks.has(line) ? `● ${line}` : String(line));
  $("editor-gutter").textContent = lines.join("\n");
  $("editor-gutter").scrollTop = editor.scrollTop;
  $("editor-errors").replaceChildren(...errors.map((error) => el("li", {
    textContent: `line ${error.line}: ${error.message}`, onclick: () => goToLine(error.line),
  })));
  $("editor-gutter").dataset.errors = errors.map((error) => error.line).join(",");
}

function goToLine(line) {
  const lines = editor.value.split("\n");
  const start = lines.slice(0, line - 1).reduce((sum, text) => sum + text.length + 1, 0);
  editor.focus();
  editor.setSelectionRange(start, start + (lines[line - 1] || "").length);
  editor.scrollTop = Math.max(0, (line - 5) * parseFloat(getComputedStyle(editor).lineHeight));
}

let checkNumber = 0;  // only the last check's answer is shown (answers may cross)
let loadNumber = 0;  // only the last load's answer fills the editor
async function check() {
  const number = ++checkNumber;
  $("editor-state").textContent = "checking…";
  const result = await send("check_program", { text: editor.value });
  if (result.status !== "DONE" || number !== checkNumber) return;
  showGutter(result.errors);
  $("editor-state").textContent = result.errors.length ? `${result.errors.length} error(s)` : `no errors · ${result.points - 1} moves`;
}

editor.addEventListener("input", () => {
  loadNumber++;  // a load still on its way must not replace what the user typed
  showGutter();
  $("editor-state").textContent = "edited";
  clearTimeout(checkTimer);
  checkTimer = setTimeout(check, 1500);  // checked once typing rests
});
editor.addEventListener("scroll", () => { $("editor-gutter").scrollTop = editor.scrollTop; });
$("editor-check").onclick = check;

async function loadEditor(name) {
  const file = name || $("editor-file").value.trim() || (state.program && state.program.name_in_prefix);
  if (!file) { notice("error", "name a program to load (in the program folder)"); return; }
  const number = ++loadNumber;
  try {
    const answer = await fetchJson(`/api/editor?file=${encodeURIComponent(file)}`);
    if (number !== loadNumber) return;
    $("editor-file").value = answer.file;
    editor.value = answer.text;
    showGutter();
    check();
  } catch (error) {
    notice("error", `editor: ${error.message.trim()}`);
  }
}
$("editor-load").onclick = () => loadEditor();

async function save(isOpening) {
  const file = $("editor-file").value.trim();
  if (!file) { notice("error", "give the program a name, e.g. part.ngc"); return; }
  const result = await send("files.put", { file, text: editor.value });
  if (result.status !== "DONE") return;
  $("editor-state").textContent = `saved ${new Date().toLocaleTimeString()}`;
  if (isOpening) send("open", { file });
  check();
}
$("editor-save").onclick = () => save(false);
$("editor-save-open").onclick = () => save(true);
loaders.editor = () => {
  if (!editor.value && state.program && state.program.name_in_prefix) loadEditor(state.program.name_in_prefix);
};

// ------------------------------------------------------------------ history
const started = new Intl.DateTimeFormat(undefined, { dateStyle: "short", timeStyle: "medium" });
on("jobs", (message) => {
  $("jobs").tBodies[0].replaceChildren(...message.jobs.map((job) => {
    const difference = job.estimate_s ? `${(((job.run_s - job.estimate_s) / job.estimate_s) * 100).toFixed(0)} %` : "—";
    return el("tr", { className: job.result },
      el("td", { textContent: started.format(new Date(job.started * 1000)) }),
      el("td", { className: "comment", textContent: job.file.split("/").pop(), title: job.file }),
      el("td", { textContent: job.result }),
      el("td", { textContent: duration(job.run_s) }),
      el("td", { textContent: job.estimate_s ? duration(job.estimate_s) : "—" }),
      el("td", { textContent: job.result === "finished" ? difference : "—" }),
      el("td", { textContent: job.paused_s >= 1 ? duration(job.paused_s) : "" }),
      el("td", { textContent: job.last_line }));
  }));
});

// ------------------------------------------------------------------ keyboard sheet, theme
const SHORTCUTS = [
  ["Esc", "STOP: abort everything (always, also while typing)"], ["F1", "E-stop on / reset"],
  ["F2", "machine on / off"], ["← → ↑ ↓", "jog X and Y (a lathe: Z and X)"], ["PgUp PgDn", "jog Z"],
  ["I / Shift+I", "next / previous jog step"], ["Ctrl+Home", "home all"],
  ["R", "run"], ["P", "pause"], ["S", "resume"], ["T", "step"],
  ["F7 / F8", "mist / flood"], ["F9 / F10", "spindle forward / reverse"], ["F11 / F12", "spindle slower / faster"],
  ["?", "this sheet"],
];
function showHelp() {
  const table = el("table", { className: "shortcuts" },
    ...SHORTCUTS.map(([key, what]) => el("tr", {}, el("th", {}, el("kbd", { textContent: key })), el("td", { textContent: what }))));
  showModal("Keyboard", [table, el("p", { className: "hint", textContent: "Jog keys and letters act when no text field has the focus." })],
    [["Close", null]]);
}
$("help").onclick = showHelp;
on("help", showHelp);

function setTheme(theme) {
  document.documentElement.dataset.theme = theme;
  localStorage.setItem("cnc.theme", theme);
  emit("theme", theme);
}
$("theme").onclick = () => setTheme(document.documentElement.dataset.theme === "dark" ? "light" : "dark");
setTheme(localStorage.getItem("cnc.theme") || "dark");

// ------------------------------------------------------------------ [DISPLAY] dialogs
// MESSAGE_* / MULTIMESSAGE_* dialogs, shown while the server says one is open (its HAL pin
// rose); the first answer from any page closes it in all of them.
on("dialog", (d) => {
  closeDialog(d.name);
  const answers = { ok: [["OK", true]], yesno: [["Yes", true], ["No", false]], none: [] }[d.kind] || [];
  const box = el("div", { className: `dialog ${d.icon.toLowerCase()}`, role: "alertdialog" },
    d.title ? el("h3", { textContent: d.title }) : null,
    el("p", { textContent: d.text }),
    d.details ? el("details", {}, el("summary", { textContent: "Details" }), d.details) : null,
    el("div", { className: "row" }, ...answers.map(([label, isYes]) => el("button", {
      textContent: label, onclick: () => send("answer", { name: d.name, is_yes: isYes }),
    }))));
  box.dataset.name = d.name;
  $("dialogs").append(box);
});
function closeDialog(name) {
  for (const box of [...$("dialogs").children]) if (box.dataset.name === name) box.remove();
}
on("dialog_close", (message) => closeDialog(message.name));

on("config", (config) => {
  document.body.classList.toggle("has-tool-sensor", Boolean(config.tool_sensor));
  buildProbeForm();
});
on("units", () => { const view = document.body.dataset.view; if (loaders[view] && view !== "editor") loaders[view](); });
