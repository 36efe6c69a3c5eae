// An in-page dialog (never the browser's prompt() or confirm(): those block the page, and
// with it the STOP button). Esc closes it, and, as everywhere, also stops the machine.

import { $, el, parseDecimal } from "./core.js";
import { notice } from "./notices.js";

let closeOpen = null;

export function closeModal() {
  if (closeOpen) closeOpen(null);
}

// Show ``content`` (elements) with buttons; resolves with the value of the button pressed
// (null when closed otherwise).
export function showModal(title, content, buttons = [["OK", true], ["Cancel", null]]) {
  closeModal();
  const box = $("modal").querySelector(".modal-box");
  return new Promise((resolve) => {
    const finish = (value) => {
      closeOpen = null;
      $("modal").hidden = true;
      box.replaceChildren();
      resolve(value);
    };
    closeOpen = finish;
    const row = el("div", { className: "row modal-buttons" },
      ...buttons.map(([label, value]) => el("button", { textContent: label, onclick: () => finish(value) })));
    box.replaceChildren(el("h3", { textContent: title }), ...content, row);
    $("modal").hidden = false;
    const first = box.querySelector("input, select, textarea") || row.firstElementChild;
    if (first) first.focus();
    box.onkeydown = (event) => {
      if (event.key === "Enter" && event.target.tagName !== "TEXTAREA") {
        event.preventDefault();
        row.firstElementChild.click();
      }
    };
  });
}

// Ask for one number (',' or '.' decimal separator); null when cancelled.
export async function askNumber(title, label, value = "0", extra = []) {
  const input = el("input", { value, inputMode: "decimal", className: "number wide" });
  while (true) {
    const answer = await showModal(title, [el("label", { className: "field" }, el("span", { textContent: label }), input), ...extra]);
    if (answer === null) return null;
    const number = parseDecimal(input.value);
    if (number !== null) return number;
    notice("error", `'${input.value}' is not a number`);
  }
}

$("modal").addEventListener("pointerdown", (event) => {
  if (event.target === $("modal")) closeModal();  // a press outside the box
});
