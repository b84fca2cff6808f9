/* What the page brought along (gui/views/pages.py, bootstrap): the catalogues,
 * the pickers' rows and the shown leg's segments, each named by what it is and
 * by whose rows they are ("of").  Each piece is taken once, by the read it
 * stands for, while the page starts; every later read asks the server. */
import { CONFIG } from "./dom.js";

const pieces = new Map(Object.entries(CONFIG.bootstrap || {}));

/* The piece `name` if it holds the rows of `of` (null for top-level lists), else undefined. */
export function take(name, of = null) {
  const piece = pieces.get(name);
  pieces.delete(name);
  return piece && piece.of === of ? piece.data : undefined;
}

/* Once the page has started, a piece not taken would be out of date. */
export function forgetBootstrap() {
  pieces.clear();
}
