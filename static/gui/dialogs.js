/* Dialogs built from field specs: nothing is written until Save, Cancel
 * discards, and the server's refusals appear next to their fields. */
import { CONFIG, $, $$ } from "./dom.js";
import { clearError, showError } from "./feedback.js";

function ensureTimeZoneList() {
  if ($("#tz-list")) return;
  const list = document.createElement("datalist");
  list.id = "tz-list";
  const zones = Intl.supportedValuesOf ? Intl.supportedValuesOf("timeZone") : ["UTC"];
  list.append(...["UTC", ...zones].map((z) => new Option(z)));
  document.body.append(list);
}

export function buildField(spec, value) {
  const label = document.createElement("label");
  label.textContent = spec.label;
  let input;
  if (spec.options) {
    input = document.createElement("select");
    if (!spec.required) input.append(new Option("—", ""));
    input.append(...spec.options.map(([v, text]) => new Option(text, v)));
    input.value = value === null || value === undefined ? "" : String(value);
  } else if (spec.type === "textarea") {
    input = document.createElement("textarea");
    input.rows = 3;
    input.value = value || "";
  } else {
    input = document.createElement("input");
    input.value = value ?? "";
    if (spec.number) input.inputMode = "decimal";
    if (spec.list) {
      ensureTimeZoneList();
      input.setAttribute("list", spec.list);
    }
  }
  input.name = spec.name;
  label.append(input);
  return label;
}

function readField(spec, form) {
  const raw = form.elements[spec.name].value;
  if (!spec.options) return raw;
  if (raw === "") return null;
  return /^\d+$/.test(raw) && typeof spec.options[0][0] === "number" ? Number(raw) : raw;
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
      await save(body);
      dialog.close();
    } catch (err) {
      showError(err, errorBox);
    }
  };
  $(".close", dialog).onclick = () => dialog.close();
  dialog.showModal();
}

export function confirmDialog(message, { yes = "Delete", no = "Keep it", warn = true } = {}) {
  const dialog = $("#confirm-dialog");
  $(".message", dialog).textContent = message;
  $(".undo-warning", dialog).hidden = !warn;
  $('button[value="yes"]', dialog).textContent = yes;
  $('button[value="no"]', dialog).textContent = no;
  dialog.returnValue = "";
  dialog.showModal();
  return new Promise((resolve) => dialog.addEventListener("close", () => resolve(dialog.returnValue === "yes"), { once: true }));
}
