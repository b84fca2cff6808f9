// ESLint (flat config) for the operator GUI's scripts, run by scripts/test.sh next to ruff.
const js = require("@eslint/js");
const globals = require("globals");

module.exports = [
  js.configs.recommended,
  {
    files: ["static/gui/**/*.js"],
    languageOptions: {
      ecmaVersion: 2022,
      sourceType: "script",
      // Leaflet comes from django-leaflet's static files; FttMaps from maps.js.
      globals: { ...globals.browser, L: "readonly", FttMaps: "writable" },
    },
    rules: {
      "no-unused-vars": ["error", { args: "none" }],
    },
  },
];
