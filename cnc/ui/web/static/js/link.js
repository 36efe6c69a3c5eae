// The websocket to the server: the public API, JSON-RPC 2.0 (cnc/ui/web/API.md), calls out,
// their responses and the notifications the page subscribed to in. Sending is immediate:
// a call is written to the socket in the same event handler that asked for it, never
// queued behind drawing or behind another call's answer.

import { emit, state, withToken } from "./core.js";
import { notice } from "./notices.js";

let socket = null;
let nextId = 1;
const pending = new Map();  // call id -> callback(response)
const RECONNECT_MS = 1000;
const REFUSED = -32000;  // the API's error code for a command the controller refused

export function isOpen() { return socket !== null && socket.readyState === WebSocket.OPEN; }

// A JSON-RPC response as the page's parts take it: {status: "DONE", ...result} or
// {status: "ERROR", message, is_reported}.
function outcome(response) {
  if (!response.error) return { status: "DONE", message: "DONE", ...response.result };
  const data = response.error.data || {};
  return { status: "ERROR", message: response.error.message, is_reported: Boolean(data.is_reported) };
}

// Call a method; the promise gets its outcome. A failure the controller reported itself
// (is_reported: the error channel's notice says it) is already a notice; others become one.
export function send(method, params = {}) {
  return call(method, params).then((response) => {
    const result = outcome(response);
    if (result.status !== "DONE" && !result.is_reported) notice("error", result.message);
    return result;
  });
}

// Call a method; the promise gets the JSON-RPC response ({result} or {error}).
function call(method, params) {
  return new Promise((resolve) => {
    if (!isOpen()) {
      resolve({ error: { code: REFUSED, message: `${method}: not connected to the server` } });
      return;
    }
    const id = nextId++;
    pending.set(id, resolve);
    socket.send(JSON.stringify({ jsonrpc: "2.0", id, method, params }));
  });
}

// A notification: no answer (continuous jog holds, ten a second).
export function sendQuietly(method, params = {}) {
  if (isOpen()) socket.send(JSON.stringify({ jsonrpc: "2.0", method, params }));
}

export function connect() {
  const scheme = location.protocol === "https:" ? "wss" : "ws";
  socket = new WebSocket(withToken(`${scheme}://${location.host}/api/v1/ws`));
  socket.onopen = async () => {
    state.isSocketOpen = true;
    emit("link", true);
    // What the page shows: its configuration, every status field, every event.
    const config = await call("page.config", {});
    if (!config.result) return;  // the connection went away meanwhile
    state.config = config.result;
    emit("config", config.result);
    const status = await call("status.subscribe", {});
    if (status.result) receive({ jsonrpc: "2.0", method: "notify.status", params: status.result });
    call("events.subscribe", {});
  };
  socket.onmessage = (event) => receive(JSON.parse(event.data));
  socket.onclose = () => {
    state.isSocketOpen = false;
    const lost = { error: { code: REFUSED, message: "connection lost", data: { is_reported: true } } };
    pending.forEach((done) => done(lost));
    pending.clear();
    emit("link", false);
    setTimeout(connect, RECONNECT_MS);
  };
}

function receive(message) {
  if (!message.method) {  // a response to a call
    const done = pending.get(message.id);
    pending.delete(message.id);
    if (done) done(message);
    else if (message.error && message.error.code !== REFUSED) notice("error", message.error.message);
    return;
  }
  if (!message.method.startsWith("notify.")) return;
  const type = message.method.slice("notify.".length);
  if (type === "status") {
    Object.assign(state.status, message.params);
    emit("status", message.params);
    return;
  }
  const body = { type, ...message.params };
  if (type === "program") state.program = body;
  emit(type, body);
}
