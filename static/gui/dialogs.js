/* Dialogs built from field specs: nothing is written until Save, Cancel
 * discards, and the server's refusals appear next to their fields. */
import { CONFIG, $, $$ } from "./dom.js";
import { clearError, showError } from "./feedback.js";
import { _ } from "./i18n.js";

/* Typed values with suggestions (time zones): one datalist per field name. */
function suggestionList(spec) {
  const id = `suggest-${spec.name}`;
  if (!document.getElementById(id)) {
    const list = document.createElement("datalist");
    list.id = id;
    list.append(...spec.suggestions.map((s) => new Option(s)));
    document.body.append(list);
  }
  return id;
}

/* One field as the server describes it (gui/forms.py): name, label, type
 * ("text", "textarea", "select", "number"), required, choices, help, suggestions. */
export function buildField(spec, value) {
  const label = document.createElement("label");
  label.textContent = spec.label;
  let input;
  if (spec.type === "select") {
    input = document.createElement("select");
    if (!spec.required) input.append(new Option("—", ""));
    else if (value === null || value === undefined || value === "") {
      // A required choice not made yet says so (and what to do when there is none).
      const hint = new Option(spec.choices.length ? "— choose —" : "none configured yet: ask an administrator", "");
      hint.disabled = true;
      input.append(hint);
    }
    input.append(...spec.choices.map(([v, text]) => new Option(text, v)));
    input.value = value === null || value === undefined ? "" : String(value);
  } else if (spec.type === "textarea") {
    input = document.createElement("textarea");
    input.rows = 3;
    input.value = value || "";
  } else {
    input = document.createElement("input");
    input.value = value ?? "";
    if (spec.type === "number") input.inputMode = "decimal";
    if (spec.max_length) input.maxLength = spec.max_length;
    if (spec.suggestions) input.setAttribute("list", suggestionList(spec));
  }
  input.name = spec.name;
  label.append(input);
  if (spec.help) {
    const help = document.createElement("small");
    help.className = "help muted";
    help.id = `help-${spec.name}`;
    help.textContent = spec.help;
    input.setAttribute("aria-describedby", help.id);
    label.append(help);
  }
  return label;
}

function readField(spec, form) {
  const raw = form.elements[spec.name].value;
  if (spec.type !== "select") return raw;
  if (raw === "") return null;
  // Ids go back as numbers, catalogue keys ("sunny") as text.
  const numeric = spec.choices.length && typeof spec.choices[0][0] === "number";
  return numeric && /^\d+$/.test(raw) ? Number(raw) : raw;
}

/* A dialog whose Save runs `save`; it stays open and shows the server's words
 * when the save is refused. */
export function formDialog({ title, subtitle, specs, values, save }) {
  const dialog = $("#form-dialog");
  const form = $("form", dialog);
  $(".title", dialog).textContent = title;
  $(".subtitle", dialog).textContent = subtitle || "";
  const errorBox = $(".dialog-error", dialog);
  clearError(errorBox);
  $(".fields", dialog).replaceChildren(...specs.map((s) => buildField(s, values[s.name])));
  const readOnly = !CONFIG.canOperate;
  $$(".fields input, .fields select, .fields textarea", dialog).forEach((el) => (el.disabled = readOnly));
  $('button[value="save"]', dialog).hidden = readOnly;
  form.onsubmit = async (e) => {
    e.preventDefault();
    const body = Object.fromEntries(specs.map((s) => [s.name, readField(s, form)]));
    clearError(errorBox);
    try {
      // A save the operator called off at a question leaves the dialog open.
      if ((await save(body)) !== false) dialog.close();
    } catch (err) {
      showError(err, errorBox);
    }
  };
  $(".close", dialog).onclick = () => dialog.close();
  dialog.showModal();
}

/* `items`: lines naming what the action touches, listed under the question. */
export function confirmDialog(message, { yes = _("Delete"), no = _("Keep it"), warn = true, items = [] } = {}) {
  const dialog = $("#confirm-dialog");
  $(".message", dialog).textContent = message;
  const list = $(".items", dialog);
  list.replaceChildren(...items.map((text) => Object.assign(document.createElement("li"), { textContent: text })));
  list.hidden = !items.length;
  $(".undo-warning", dialog).hidden = !warn;
  $('button[value="yes"]', dialog).textContent = yes;
  $('button[value="no"]', dialog).textContent = no;
  dialog.returnValue = "";
  dialog.showModal();
  return new Promise((resolve) => dialog.addEventListener("close", () => resolve(dialog.returnValue === "yes"), { once: true }));
}
