/* A Leaflet map for the comparison page's search and routes: the cockpit's
 * tiles when the server names a tile source, otherwise a plain background.
 * canvas: for thousands of points (the search); routes stay SVG paths. */
import { CONFIG } from "./dom.js";

export function plainMap(element, { canvas = false } = {}) {
  const map = L.map(element, { preferCanvas: canvas, worldCopyJump: true }).setView([20, 0], 2);
  if (CONFIG.tileUrl) L.tileLayer(CONFIG.tileUrl, { maxZoom: 21, maxNativeZoom: 19, attribution: CONFIG.tileAttribution }).addTo(map);
  return map;
}

/* [[lon, lat], ...] as Leaflet's [lat, lon]. */
export const latLngs = (points) => points.map(([lon, lat]) => [lat, lon]);
