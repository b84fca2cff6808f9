/* The language picker (templates/language_picker.html) sends itself on a change. */
for (const form of document.querySelectorAll("form.language-picker")) {
  form.querySelector(".language-apply").hidden = true;
  form.querySelector("select").addEventListener("change", () => form.requestSubmit());
}
