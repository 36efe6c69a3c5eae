// Notices: one toast per event (the server gathers the lines of one error), which expires
// by itself and never covers the listing for long; every notice is also kept in the
// message log (the ✉ button), where errors count until it is opened.

import { $, el, on } from "./core.js";

export const LIFETIME_MS = { error: 12000, text: 6000, display: 8000 };
const MAX_SHOWN = 3;
const LOG_KEPT = 100;
const REPEAT_MS = 5000;  // the same text again within this: counted on the same toast
let unread = 0;

export function notice(kind, text, details = []) {
  addToLog(kind, text, details);
  const box = $("notices");
  const last = box.firstElementChild;
  if (last && last.dataset.text === text && Date.now() - Number(last.dataset.time) < REPEAT_MS) {
    const count = Number(last.dataset.count || 1) + 1;
    last.dataset.count = count;
    last.dataset.time = Date.now();
    last.querySelector(".count").textContent = `×${count}`;
    restartTimer(last, kind);
    return;
  }
  const toast = el("div", { className: `notice ${kind}`, role: kind === "error" ? "alert" : "status" },
    el("span", { className: "text", textContent: text }),
    el("span", { className: "count" }),
    el("button", { textContent: "×", title: "Dismiss", onclick: () => toast.remove() }));
  toast.dataset.text = text;
  toast.dataset.time = Date.now();
  if (details.length) {
    toast.querySelector(".text").append(
      el("details", {}, el("summary", { textContent: `${details.length} more` }), details.join("\n")));
  }
  toast.addEventListener("pointerenter", () => clearTimeout(toast.timer));
  toast.addEventListener("pointerleave", () => restartTimer(toast, kind));
  box.prepend(toast);
  restartTimer(toast, kind);
  while (box.children.length > MAX_SHOWN) box.lastElementChild.remove();
}

function restartTimer(toast, kind) {
  clearTimeout(toast.timer);
  toast.timer = setTimeout(() => toast.remove(), LIFETIME_MS[kind] || LIFETIME_MS.text);
}

function addToLog(kind, text, details) {
  const list = $("notice-log").querySelector("ol");
  const time = new Date().toLocaleTimeString();
  list.prepend(el("li", { className: kind }, el("time", { textContent: time }), ` ${text}`,
    details.length ? el("div", { className: "details", textContent: details.join("\n") }) : null));
  while (list.children.length > LOG_KEPT) list.lastElementChild.remove();
  if (kind === "error" && $("notice-log").hidden) {
    unread += 1;
    $("notice-count").textContent = unread;
  }
}

$("notice-log-button").addEventListener("click", () => {
  $("notice-log").hidden = !$("notice-log").hidden;
  unread = 0;
  $("notice-count").textContent = "";
});

on("notice", (message) => notice(message.kind, message.text, message.details || []));
