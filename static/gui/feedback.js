/* Feedback that does not move the layout: toasts for the page, messages next
 * to their fields inside dialogs. */
import { $, $$ } from "./dom.js";
import { ApiError, plainMessage } from "./api.js";
import { _ } from "./i18n.js";

export function showError(error, where) {
  // Inside a dialog, field errors go next to their fields; the rest to the dialog's box.
  if (where && error instanceof ApiError && showFieldErrors(error, where.closest("dialog"))) {
    where.textContent = _("Please correct the marked fields.");
    where.hidden = false;
    where.scrollIntoView({ block: "nearest" });
    return;
  }
  const box = where || $("#error");
  const text = plainMessage(error);
  if (box.id === "error") {
    $(".text", box).textContent = text;
  } else {
    box.textContent = text;
    box.scrollIntoView({ block: "nearest" });
  }
  box.hidden = false;
}

/* Puts each server message under the field it names, in the field's own label. */
function showFieldErrors(error, dialog) {
  if (!dialog) return false;
  $$(".field-error", dialog).forEach((el) => el.remove());
  let shown = 0;
  for (const [field, messages] of Object.entries(error.errors || {})) {
    const input = dialog.querySelector(`[name="${CSS.escape(field)}"]`);
    if (!input) continue;
    const p = document.createElement("p");
    p.className = "field-error error";
    p.id = `error-${field}`;
    const label = input.closest("label");
    const name = label ? label.firstChild.textContent.trim() : field;
    p.textContent = `${name}: ${[].concat(messages).join(" ")}`;
    input.setAttribute("aria-invalid", "true");
    input.setAttribute("aria-describedby", p.id);
    input.after(p);
    if (!shown) input.focus();
    shown += 1;
  }
  return shown > 0;
}

export function clearError(where) {
  const box = where || $("#error");
  box.hidden = true;
  const dialog = where && where.closest("dialog");
  if (dialog) {
    $$(".field-error", dialog).forEach((el) => el.remove());
    $$("[aria-invalid]", dialog).forEach((el) => el.removeAttribute("aria-invalid"));
  }
}

$("#error .dismiss").addEventListener("click", () => clearError());

export function notice(text) {
  const box = $("#notice");
  box.textContent = text;
  box.hidden = false;
  clearTimeout(notice.timer);
  notice.timer = setTimeout(() => (box.hidden = true), 4000);
}
