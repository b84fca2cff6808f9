/* The cockpit's two maps (GPS and local map frame): follow or fit, tiles and
 * basemaps, the shift's local map image and its overlay on the GPS map. */
import { CONFIG, $ } from "./dom.js";
import { api } from "./api.js";
import { showError } from "./feedback.js";
import { segmentLabel, state } from "./state.js";
import { roundFloat } from "./format.js";
import { GpsMap, LocalMap } from "./maps.js";

export const gpsMap = new GpsMap($("#gps-map"), $("#tile-message"));
export const localMap = new LocalMap($("#local-map"));
for (const m of [gpsMap, localMap]) m.labelOf = (id) => segmentLabel(id);

/* The leg's tracks thinned for the GPS map's size (the local map is laid out
 * the same), so a 200 000-point leg crosses the wire as a few thousand points.
 * Zoomed in, each map fetches the area in view in detail (TrackMap.followView). */
export async function loadLegTracks(leg) {
  // The element's size: Leaflet's getSize() still holds the size from before the
  // maps section was shown.  fitAll pads by 20 px on each side.
  const shown = [gpsMap, localMap].map((m) => m.element).find((e) => e.clientWidth > 40 && e.clientHeight > 40);
  const fit = shown ? `${shown.clientWidth - 40},${shown.clientHeight - 40}` : "800,600";
  return api("GET", `legs/${leg}/tracks/?fit=${fit}`, undefined, { root: CONFIG.guiApiRoot });
}

/* Draws the answer of loadLegTracks; only the segments not drawn yet unless redraw. */
export function drawLegTracks(data, redraw = true) {
  gpsMap.overviewZoom = data.zoom;
  localMap.overviewZoom = data.local_zoom;
  for (const [id, t] of Object.entries(data.segments)) {
    if (!redraw && state.tracks[id]) continue;
    const sid = Number(id);
    if (t.gps.length) gpsMap.setTrack(sid, t.mode, t.gps);
    if (t.local.length) localMap.setTrack(sid, t.mode, t.local);
  }
}

for (const [map, name] of [[gpsMap, "gps"], [localMap, "local"]]) {
  map.followView(async (bbox, zoom, signal) => {
    const leg = state.selected.leg;
    const query = new URLSearchParams({ map: name, bbox: bbox.map((v) => v.toFixed(7)).join(","), bbox_zoom: zoom });
    if (map.overviewZoom !== null) query.set("zoom", map.overviewZoom);
    const data = await api("GET", `legs/${leg}/tracks/?${query}`, undefined, { root: CONFIG.guiApiRoot, signal });
    return data && data.leg === state.selected.leg ? data.segments : {};
  }, showError);
}

/* Follow the vehicle (pan to each new point) or show the whole track. */
function setFollow(on) {
  gpsMap.follow = localMap.follow = on;
  $("#follow").checked = on;
  localStorage.setItem("ftt.follow", on ? "1" : "0");
}
setFollow(localStorage.getItem("ftt.follow") !== "0");
$("#follow").addEventListener("change", (e) => setFollow(e.target.checked));
$("#fit-track").addEventListener("click", () => {
  setFollow(false);
  gpsMap.fitAll();
  localMap.fitAll();
});

export function tileUrl() {
  const own = localStorage.getItem("ftt.tileUrl");
  return own !== null ? own : CONFIG.tileUrl;
}
gpsMap.setTiles(tileUrl(), CONFIG.tileAttribution);

export async function loadBasemaps() {
  const event = state.selected.event;
  if (state.basemapsOf === event) return;
  state.basemapsOf = event;
  const query = event ? `?event=${event}` : "";
  const data = await api("GET", `basemaps/${query}`, undefined, { root: CONFIG.guiApiRoot });
  gpsMap.setBasemaps(data.layers);
}

export function showMaps() {
  $("#gps-map").hidden = !$("#show-gps").checked;
  $("#local-map").hidden = !$("#show-local").checked;
  $("#local-message").hidden = !$("#show-local").checked || !$("#local-message").textContent;
  gpsMap.invalidate();
  localMap.invalidate();
}
$("#show-gps").addEventListener("change", showMaps);
$("#show-local").addEventListener("change", showMaps);

export async function loadLocalMap() {
  const shift = state.selected.shift;
  if (!shift) return;
  const data = await api("GET", `shifts/${shift}/local-map/`, undefined, { root: CONFIG.guiApiRoot });
  if (shift !== state.selected.shift) return;
  state.localMapOf = shift;
  const message = $("#local-message");
  if (data.map) {
    localMap.setMapImage(data.map);
    message.textContent = `Map "${data.map.frame}", ${data.map.width}×${data.map.height} cells of ${roundFloat(data.map.resolution)} m.`;
    if (!$("#show-local").checked) {
      $("#show-local").checked = true;
      showMaps();
    }
  } else {
    localMap.removeMapImage();
    message.textContent = "No map received for this shift yet.";
  }
  const o = data.overlay;
  if (o.available && o.corners && data.map) {
    gpsMap.setOverlay(data.map.url, o.corners);
    $("#overlay-message").textContent = `Local map over GPS: fitted from ${o.pairs} segments, scale ${o.scale.toFixed(3)}, rotation ${o.rotation_deg.toFixed(1)}°, error ${o.rms_m.toFixed(2)} m.`;
  } else {
    gpsMap.removeOverlay();
    $("#overlay-message").textContent = data.map ? o.detail || "" : "";
  }
  showMaps();
}

$("#open-map-settings").addEventListener("click", () => {
  const d = $("#map-settings-dialog");
  $("#site-tile-url").textContent = CONFIG.tileUrl || "(none)";
  $("input[name=tileUrl]", d).value = localStorage.getItem("ftt.tileUrl") || "";
  d.returnValue = "";
  d.showModal();
});
$("#map-settings-dialog").addEventListener("close", (e) => {
  const d = e.target;
  if (d.returnValue === "save") {
    const value = $("input[name=tileUrl]", d).value.trim();
    if (value) localStorage.setItem("ftt.tileUrl", value);
    else localStorage.removeItem("ftt.tileUrl");
  } else if (d.returnValue === "reset") localStorage.removeItem("ftt.tileUrl");
  else return;
  gpsMap.setTiles(tileUrl(), CONFIG.tileAttribution);
});
