/* The cockpit's two maps (GPS and local map frame): follow or fit, tiles and
 * basemaps, the shift's local map image and its overlay on the GPS map. */
import { CONFIG, $ } from "./dom.js";
import { api } from "./api.js";
import { showError } from "./feedback.js";
import { segmentLabel, state } from "./state.js";
import { fmtNumber, roundFloat } from "./format.js";
import { _ } from "./i18n.js";
import { GpsMap, LocalMap } from "./maps.js";

export const gpsMap = new GpsMap($("#gps-map"), $("#tile-message"));
export const localMap = new LocalMap($("#local-map"));
for (const m of [gpsMap, localMap]) m.labelOf = (id) => segmentLabel(id);

/* The leg's tracks thinned for the GPS map's size (the local map is laid out
 * the same), so a 200 000-point leg crosses the wire as a few thousand points.
 * Zoomed in, each map fetches the area in view in detail (TrackMap.followView). */
function fitSize() {
  // The element's size: Leaflet's getSize() still holds the size from before the
  // maps section was shown.  fitAll pads by 20 px on each side.
  const shown = [gpsMap, localMap].map((m) => m.element).find((e) => e.clientWidth > 40 && e.clientHeight > 40);
  return shown ? `${shown.clientWidth - 40},${shown.clientHeight - 40}` : "800,600";
}

/* The tracks of the leg in the address, asked for while the module loads:
 * with the page's first reads rather than after the pickers are filled. */
let early = null; // {leg, fit, answer}
let drawnLeg = null; // the leg whose tracks the maps show

export function loadLegTracks(leg) {
  const fit = fitSize();
  // Taken once: later reads (live updates) need a fresh answer.
  const first = early && early.leg === leg ? early : null;
  if (first) early = null;
  if (first && first.fit === fit) return first.answer;
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

/* The selected leg's tracks, take-overs and fitted view, drawn once: by
 * whichever comes first of the early answer and the page's own request. */
export async function showLegTracks(leg) {
  const data = await loadLegTracks(leg);
  if (leg === state.selected.leg) firstDrawing(leg, data);
  return data;
}

function firstDrawing(leg, data) {
  if (drawnLeg === leg) return;
  drawnLeg = leg;
  drawLegTracks(data);
  placeRobot(data.segments);
  showTakeOvers(null, data.segments);
  const anyLocal = Object.values(data.segments).some((t) => t.local.length);
  if (anyLocal && !$("#show-local").checked) {
    $("#show-local").checked = true;
    showMaps();
  }
  for (const m of [gpsMap, localMap]) {
    m.invalidate();
    // At once: an animated zoom would draw the canvas again a quarter second later.
    m.fitAll({ animate: false });
  }
}

/* The robot's marker at the end of the newest track of each map; when that
 * fix was made the answer does not say, so the marker starts greyed until the
 * live feed brings the next one (showPosition). */
function placeRobot(segments) {
  const newest = Object.keys(segments).map(Number).sort((a, b) => b - a);
  for (const [map, key] of [[gpsMap, "gps"], [localMap, "local"]]) {
    const id = newest.find((i) => segments[i][key].length);
    if (id !== undefined) map.setRobot(segments[id][key].at(-1));
  }
}

/* A live fix: the marker moves there, fresh, turned by the heading where known. */
export function showPosition(map, point, heading) {
  map.setRobot(point, heading ?? null, Date.now());
}

/* Empties both maps for another leg; the leg drawn (or about to be drawn)
 * from the early answer stays. */
export function clearMaps(leg) {
  if (leg !== null && drawnLeg === leg) return;
  if (leg !== null && drawnLeg === null && early && early.leg === leg) return;
  // Another leg: the early answer is of no use any more.
  early = null;
  drawnLeg = null;
  gpsMap.clear();
  localMap.clear();
}

/* Take-over circles where each ITO master starts: its start position, else
 * its track's first point.  From the segment rows once the list is loaded,
 * else from the tracks answer, which carries the same positions. */
export function showTakeOvers(segments, tracks) {
  const spots = { gps: [], local: [] };
  if (segments && segments.length) {
    for (const s of segments) {
      if (s.parent !== null || s.segment_type !== "ito") continue;
      const t = tracks[s.id];
      const local = s.start_local_x !== null && s.start_local_x !== undefined ? [s.start_local_x, s.start_local_y] : null;
      addSpots(spots, s.id, s.start_position ? [s.start_position.coordinates[1], s.start_position.coordinates[0]] : null, local, t);
    }
  } else {
    for (const [id, t] of Object.entries(tracks)) if (t.ito) addSpots(spots, Number(id), t.start, t.start_local, t);
  }
  gpsMap.setTakeOvers(spots.gps);
  localMap.setTakeOvers(spots.local);
}

function addSpots(spots, id, gps, local, t) {
  const g = gps || (t && t.gps[0]);
  if (g) spots.gps.push([id, g]);
  const l = local || (t && t.local[0]);
  if (l) spots.local.push([id, l]);
}

if (state.selected.leg && !state.view) {
  $("#maps-section").hidden = false;
  const leg = state.selected.leg;
  early = { leg, fit: fitSize(), answer: null };
  early.answer = api("GET", `legs/${leg}/tracks/?fit=${early.fit}`, undefined, { root: CONFIG.guiApiRoot });
  // Errors reach the page through its own request, which takes this answer.
  early.answer.then((data) => leg === state.selected.leg && firstDrawing(leg, data), () => {});
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
    message.textContent = _("Map \"%(frame)s\", %(width)s×%(height)s cells of %(resolution)s m.", { frame: data.map.frame, width: data.map.width, height: data.map.height, resolution: fmtNumber(roundFloat(data.map.resolution)) });
    if (!$("#show-local").checked) {
      $("#show-local").checked = true;
      showMaps();
    }
  } else {
    localMap.removeMapImage();
    message.textContent = _("No map received for this shift yet.");
  }
  const o = data.overlay;
  if (o.available && o.corners && data.map) {
    gpsMap.setOverlay(data.map.url, o.corners);
    $("#overlay-message").textContent = _("Local map over GPS: fitted from %(pairs)s segments, scale %(scale)s, rotation %(rotation)s°, error %(error)s m.", { pairs: o.pairs, scale: fmtNumber(o.scale, 3), rotation: fmtNumber(o.rotation_deg, 1), error: fmtNumber(o.rms_m, 2) });
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
