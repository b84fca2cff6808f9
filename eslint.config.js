// ESLint (flat config) for the operator GUI's ES modules, run by scripts/test.sh next to ruff.
const js = require("@eslint/js");
const globals = require("globals");

module.exports = [
  js.configs.recommended,
  {
    files: ["static/gui/**/*.js"],
    languageOptions: {
      ecmaVersion: 2022,
      sourceType: "module",
      // Leaflet comes from django-leaflet's static files as the global L.
      // gettext and ngettext come from Django's JavaScriptCatalog (/jsi18n/, static/gui/i18n.js).
      globals: { ...globals.browser, L: "readonly", gettext: "readonly", ngettext: "readonly" },
    },
    rules: {
      "no-unused-vars": ["error", { args: "none" }],
    },
  },
  {
    // The service worker runs in its own scope (self, caches, clients).
    files: ["static/gui/sw.js"],
    languageOptions: { sourceType: "script", globals: { ...globals.serviceworker } },
  },
];
