// The websocket to the server: commands out, status and messages in (protocol:
// cnc/ui/web/server.py). Sending is immediate: a command is written to the socket in the
// same event handler that asked for it, never queued behind drawing.

import { emit, state, withToken } from "./core.js";
import { notice } from "./notices.js";

let socket = null;
let nextId = 1;
const pending = new Map();  // command id -> callback(result)
const RECONNECT_MS = 1000;

export function isOpen() { return socket !== null && socket.readyState === WebSocket.OPEN; }

// Send a command; the promise gets the server's result {status, message, ...}. A failure
// the controller reported itself (is_reported) is already a notice; others become one.
export function send(cmd, args = {}) {
  return new Promise((resolve) => {
    if (!isOpen()) {
      notice("error", `${cmd}: not connected to the server`);
      resolve({ status: "ERROR", message: "not connected" });
      return;
    }
    const id = nextId++;
    pending.set(id, (result) => {
      if (result.status !== "DONE" && !result.is_reported) notice("error", result.message);
      resolve(result);
    });
    socket.send(JSON.stringify({ cmd, id, ...args }));
  });
}

// A request without an answer when it goes well (continuous jog holds).
export function sendQuietly(cmd, args = {}) {
  if (isOpen()) socket.send(JSON.stringify({ cmd, ...args }));
}

export function connect() {
  const scheme = location.protocol === "https:" ? "wss" : "ws";
  socket = new WebSocket(withToken(`${scheme}://${location.host}/ws`));
  socket.onopen = () => { state.isSocketOpen = true; emit("link", true); };
  socket.onmessage = (event) => receive(JSON.parse(event.data));
  socket.onclose = () => {
    state.isSocketOpen = false;
    pending.forEach((done) => done({ status: "ERROR", message: "connection lost", is_reported: true }));
    pending.clear();
    emit("link", false);
    setTimeout(connect, RECONNECT_MS);
  };
}

function receive(message) {
  if (message.type === "result") {
    const done = pending.get(message.id);
    pending.delete(message.id);
    if (done) done(message);
    else if (message.status !== "DONE" && !message.is_reported) notice("error", message.message);
    return;
  }
  if (message.type === "config") state.config = message.data;
  else if (message.type === "status") Object.assign(state.status, message.data);
  else if (message.type === "program") state.program = message;
  emit(message.type, message.type === "config" || message.type === "status" ? message.data : message);
}
