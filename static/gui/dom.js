/* The page's settings (the template's json_script) and DOM shorthands, shared by
 * every module of the operator GUI (see docs/gui.md). */

export const CONFIG = JSON.parse(document.getElementById("gui-config").textContent);
export const $ = (sel, root = document) => root.querySelector(sel);
export const $$ = (sel, root = document) => Array.from(root.querySelectorAll(sel));

/* A new element with properties and children. */
export function element(tag, props = {}, children = []) {
  const node = Object.assign(document.createElement(tag), props);
  node.append(...children);
  return node;
}
