/* Strings and numbers in the page's language. Django's JavaScriptCatalog (/jsi18n/,
 * loaded by templates/base.html before any module) defines gettext and ngettext;
 * `bash scripts/messages.sh` collects every _("…") and ngettext("…", "…", n). */

/* The page's language, as the server chose it (<html lang>): Intl formats with it. */
export const LANGUAGE = document.documentElement.lang || "en";

/* Fills %(name)s; without the catalogue (offline) the English text still reads. */
function fill(text, values) {
  return values ? text.replace(/%\(([a-z_]+)\)s/g, (all, key) => (key in values ? String(values[key]) : all)) : text;
}

/* _("Shift %(number)s", { number: 3 }): translated, then the named values filled in. */
export function _(text, values) {
  return fill(typeof gettext === "function" ? gettext(text) : text, values);
}

/* plural(ngettext("%(count)s take-over", "%(count)s take-overs", n), n): the count filled in. */
export function plural(text, count, values = {}) {
  return fill(text, { count, ...values });
}
