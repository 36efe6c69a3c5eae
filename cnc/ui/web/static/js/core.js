// What every part of the page shares: the state the server sent, events between parts,
// and small helpers (numbers, units, elements). No framework, no build step.

export const $ = (id) => document.getElementById(id);

// The state the server sent: config once per connection, status merged from diffs, the
// open program's analysis ("program" messages).
export const state = {
  config: null,
  status: { is_connected: false },
  program: null,
  isSocketOpen: false,
};

// Events: "config", "status", "program", "jobs", "probe", ... (the server's message types)
// and the page's own ("units").
const listeners = new Map();
export function on(type, listener) {
  if (!listeners.has(type)) listeners.set(type, []);
  listeners.get(type).push(listener);
}
export function emit(type, data) {
  for (const listener of listeners.get(type) || []) {
    try {
      listener(data);
    } catch (error) {
      console.error(`while handling ${type}:`, error);  // one broken part never stops the rest
    }
  }
}

const token = new URLSearchParams(location.search).get("token");
export function withToken(path) {
  return token ? `${path}${path.includes("?") ? "&" : "?"}token=${encodeURIComponent(token)}` : path;
}

export async function fetchJson(path) {
  const response = await fetch(withToken(path));
  if (!response.ok) throw new Error(await response.text());
  return response.json();
}

// A number typed by the operator: ',' or '.' as decimal separator (at most one), spaces as
// thousands separators (GUI-003); null if it is not one.
export function parseDecimal(text) {
  const compact = String(text).trim().replace(/ /g, "");
  if ((compact.match(/[.,]/g) || []).length > 1) return null;
  if (!/^[+-]?([0-9]+[.,]?[0-9]*|[.,][0-9]+)$/.test(compact)) return null;
  return parseFloat(compact.replace(",", "."));
}

// ------------------------------------------------------------------ units
// Lengths arrive in machine units; the operator may show them in mm or inches.
export const MM_PER_INCH = 25.4;
export function machineUnits() { return state.config ? state.config.units : "mm"; }
export function shownUnits() { return localStorage.getItem("cnc.units") || machineUnits(); }
export function setShownUnits(units) { localStorage.setItem("cnc.units", units); emit("units", units); }
// Machine units -> shown units, and back.
export function toShown(value) {
  if (value === null || value === undefined) return value;
  const from = machineUnits(), to = shownUnits();
  if (from === to) return value;
  return to === "inch" ? value / MM_PER_INCH : value * MM_PER_INCH;
}
export function fromShown(value) {
  const from = shownUnits(), to = machineUnits();
  if (from === to) return value;
  return to === "inch" ? value / MM_PER_INCH : value * MM_PER_INCH;
}
export function places() { return shownUnits() === "inch" ? 4 : 3; }

export function fixed(value, digits = places()) {
  return value === null || value === undefined || Number.isNaN(value) ? "—" : Number(value).toFixed(digits);
}
export function length(value) { return fixed(toShown(value)); }

// 1:02:03, 2:03 or 0:05
export function duration(seconds) {
  if (seconds === null || seconds === undefined) return "—";
  const total = Math.max(0, Math.round(seconds));
  const h = Math.floor(total / 3600), m = Math.floor((total % 3600) / 60), s = total % 60;
  const two = (n) => String(n).padStart(2, "0");
  return h ? `${h}:${two(m)}:${two(s)}` : `${m}:${two(s)}`;
}

// ------------------------------------------------------------------ elements
export function el(tag, props = {}, ...children) {
  const element = document.createElement(tag);
  for (const [key, value] of Object.entries(props)) {
    if (key === "dataset") Object.assign(element.dataset, value);
    else if (key.startsWith("on")) element.addEventListener(key.slice(2), value);
    else if (key in element) element[key] = value;
    else element.setAttribute(key, value);
  }
  element.append(...children.filter((child) => child !== null && child !== undefined));
  return element;
}

// Change a text only when it differs: an unchanged page costs the browser no layout.
export function setText(element, text) {
  const value = String(text);
  if (element.textContent !== value) element.textContent = value;
}

// Whether the operator is typing (keys then belong to the field, not to jogging).
export function isTyping() {
  const active = document.activeElement;
  if (!active) return false;
  if (active.tagName === "TEXTAREA" || active.isContentEditable) return true;
  return active.tagName === "INPUT" && !["range", "checkbox", "radio", "button"].includes(active.type);
}
