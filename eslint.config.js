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
      // Text from the server (a test case's title, a vehicle's name) is shown, never
      // parsed: Leaflet puts a string given as a tooltip or popup into innerHTML.
      "no-restricted-syntax": [
        "error",
        {
          selector: "AssignmentExpression > MemberExpression.left[property.name=/^(innerHTML|outerHTML)$/]",
          message: "Build elements (dom.js element, textContent): a string assigned here is parsed as HTML.",
        },
        {
          selector: "CallExpression[callee.property.name='insertAdjacentHTML']",
          message: "Build elements (dom.js element, textContent): this string is parsed as HTML.",
        },
        {
          selector:
            "CallExpression[callee.property.name=/^(bindTooltip|bindPopup|setTooltipContent|setPopupContent)$/] > " +
            ":not(CallExpression[callee.name='element'], ArrowFunctionExpression[body.callee.name='element']).arguments:first-child",
          message: "Give Leaflet an element (dom.js element, textContent): a string is parsed as HTML.",
        },
      ],
    },
  },
  {
    // The service worker runs in its own scope (self, caches, clients).
    files: ["static/gui/sw.js"],
    languageOptions: { sourceType: "script", globals: { ...globals.serviceworker } },
  },
];
