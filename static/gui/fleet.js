/* The fleet view: every vehicle that is logging, on one map, for a test
 * director running several robots.  Opening it takes the fleet the page brought
 * along (or reads /gui/api/fleet/ once);
 * after that each robot's mode and position arrive over the live link and are
 * applied to its entry (apply); only what the events cannot say (a vehicle
 * that starts or stops logging, a collector's state) is read again.  One tap
 * on a vehicle opens its cockpit. */
import { CONFIG, $, element } from "./dom.js";
import { api } from "./api.js";
import { showError } from "./feedback.js";
import { modeName, saveUrl, state } from "./state.js";
import { fmtDuration } from "./format.js";
import { _ } from "./i18n.js";
import { COLORS, GpsMap } from "./maps.js";
import { gpsMap, localMap, showMaps, tileUrl } from "./mapview.js";
import { Live } from "./live.js";
import { loadLevel } from "./levels.js";
import { take } from "./bootstrap.js";

const NO_MODE = "#6b7785";
// What needs a re-read is read at most this often.
const MIN_INTERVAL_MS = 1000;

export const Fleet = {
  map: null,
  tiles: undefined,
  vehicles: [],
  markers: new Map(), // vehicle id -> circle marker
  fitted: new Set(), // vehicle ids the view was last fitted to
  lastRead: 0,
  timer: null,
  frame: null,
  listStale: false, // the next frame redraws the list too, not only the dots
  basemapsOf: null, // the test events (ids, joined) whose basemaps the switcher offers

  visible() {
    return state.view === "fleet";
  },

  ensureMap() {
    if (!this.map) {
      this.map = new GpsMap($("#fleet-map"), $("#fleet-tile-message"));
    }
    if (this.tiles !== tileUrl()) {
      this.tiles = tileUrl();
      this.map.setTiles(this.tiles, CONFIG.tileAttribution);
    }
  },

  /* Switches between the fleet and the cockpit; the choice is kept in the address. */
  async show(on, { fromHistory = false } = {}) {
    const switching = (state.view === "fleet") !== on;
    state.view = on ? "fleet" : null;
    saveUrl({ push: switching && !fromHistory });
    $("#fleet-view").hidden = !on;
    $("#cockpit").hidden = on;
    // The button names where it leads.
    const toggle = $("#toggle-fleet");
    toggle.textContent = on ? _("Cockpit") : _("Fleet");
    toggle.title = on ? _("Back to the selected leg") : _("Every vehicle that is logging, on one map");
    Live.subscribe();
    if (!on) {
      // The cockpit's maps were measured (and fitted) while hidden.
      showMaps();
      gpsMap.fitAll();
      localMap.fitAll();
      return;
    }
    this.ensureMap();
    this.map.invalidate();
    await this.refresh({ now: true });
  },

  async refresh({ now = false } = {}) {
    if (!this.visible()) return;
    const wait = this.lastRead + MIN_INTERVAL_MS - Date.now();
    if (!now && wait > 0) {
      if (!this.timer) this.timer = setTimeout(() => this.refresh().catch(showError), wait);
      return;
    }
    clearTimeout(this.timer);
    this.timer = null;
    this.lastRead = Date.now();
    // Opening the view, the page brought the fleet along: no request to wait for.
    const data = take("fleet") ?? (await api("GET", "fleet/", undefined, { root: CONFIG.guiApiRoot }));
    this.vehicles = data.vehicles;
    // The vehicles are shown before the basemaps are asked for: they do not wait on them.
    this.render();
    await this.loadBasemaps();
  },

  /* A segment or poses event of the change feed: it carries its vehicle's entry
   * as the server computes it (live.consumers), put in place of the old. */
  apply(e) {
    if (!this.visible()) return;
    const entry = e.fleet;
    const at = entry ? this.vehicles.findIndex((x) => x.vehicle.id === entry.vehicle.id) : -1;
    if (at < 0) {
      Live.later("fleet"); // a vehicle not on the map yet, or no longer logging into this leg
      return;
    }
    const before = this.vehicles[at];
    this.vehicles[at] = entry;
    // A new mode is what the director watches for: drawn now, not at the next
    // frame (a switch is rare; positions, many a second, wait for the frame).
    if (entry.mode !== before.mode || entry.mode_since !== before.mode_since) {
      this.listStale = false;
      this.render();
      return;
    }
    // The list says "no position yet" until the first one.
    this.listStale ||= !before.position !== !entry.position || entry.last_takeover !== before.last_takeover || entry.collector.online !== before.collector.online;
    // Several robots' events in one frame are drawn once; positions alone move
    // the dots and leave the list as it is.
    if (!this.frame) {
      this.frame = requestAnimationFrame(() => {
        this.frame = null;
        const list = this.listStale;
        this.listStale = false;
        this.render({ list });
      });
    }
  },

  /* The switcher's layers, starting on the basemap the logging robots' test events
   * start on (the server decides which); asked again when those events change. */
  async loadBasemaps() {
    const events = [...new Set(this.vehicles.map((v) => v.leg.test_event))].sort((a, b) => a - b);
    const key = events.join(",");
    if (this.basemapsOf === key) return;
    this.basemapsOf = key;
    const query = new URLSearchParams(events.map((e) => ["event", e]));
    const data = await api("GET", `basemaps/?${query}`, undefined, { root: CONFIG.guiApiRoot });
    this.map.setBasemaps(data.layers);
  },

  color(v) {
    return COLORS[v.mode] || NO_MODE;
  },

  describe(v) {
    const mode = v.mode ? modeName(v.mode) : _("no open segment");
    const takeover = v.last_takeover ? _("last take-over %(duration)s ago", { duration: fmtDuration(v.last_takeover, null) }) : _("no take-over yet");
    const where = v.leg.location || _("Test event #%(id)s", { id: v.leg.test_event });
    const leg = `${where} · ${_("Shift %(number)s", { number: v.leg.shift_number })} · ${_("Leg %(number)s", { number: v.leg.number })}`;
    return { mode, takeover, leg };
  },

  render({ list = true } = {}) {
    if (!this.map) return;
    const seen = new Set();
    for (const v of this.vehicles) {
      const id = v.vehicle.id;
      seen.add(id);
      let marker = this.markers.get(id);
      if (!v.position) {
        if (marker) marker.remove();
        this.markers.delete(id);
        continue;
      }
      const style = { radius: 11, color: "#fff", weight: 3, fillColor: this.color(v), fillOpacity: 1, className: `fleet-marker vehicle-${id}` };
      if (!marker) {
        marker = L.circleMarker(v.position, style).addTo(this.map.map);
        // "auto": right of a dot in the map's left half, left of it in the right half, so a
        // dot near the edge (on a phone every dot is) keeps its name on the map.
        marker.bindTooltip(element("span", { textContent: v.vehicle.name }), { permanent: true, direction: "auto", offset: [10, 0] });
        marker.on("click", () => this.open(marker.vehicle));
        this.markers.set(id, marker);
      } else {
        marker.setLatLng(v.position);
        marker.setStyle(style);
      }
      marker.vehicle = v;
      marker.getElement()?.setAttribute("data-mode", v.mode || "none");
    }
    for (const [id, marker] of this.markers) {
      if (seen.has(id)) continue;
      marker.remove();
      this.markers.delete(id);
    }
    // A new vehicle on the map is brought into view; otherwise the view stays where it was put.
    const ids = new Set(this.markers.keys());
    if ([...ids].some((id) => !this.fitted.has(id))) this.fitAll();
    if (list) this.renderList();
  },

  fitAll() {
    const points = [...this.markers.values()].map((m) => m.getLatLng());
    this.fitted = new Set(this.markers.keys());
    if (!points.length) return;
    this.map.map.fitBounds(L.latLngBounds(points), { maxZoom: 18, padding: [40, 40] });
  },

  renderList() {
    const list = $("#fleet-list");
    $("#fleet-empty").hidden = this.vehicles.length > 0;
    list.replaceChildren(...this.vehicles.map((v) => {
      const { mode, takeover, leg } = this.describe(v);
      const b = document.createElement("button");
      b.type = "button";
      b.className = "fleet-vehicle";
      b.dataset.vehicle = v.vehicle.id;
      b.dataset.mode = v.mode || "none";
      const dot = document.createElement("span");
      dot.className = "dot";
      dot.style.background = this.color(v);
      const name = document.createElement("strong");
      name.textContent = v.vehicle.name;
      const modeWord = document.createElement("span");
      modeWord.className = "mode-word";
      modeWord.textContent = mode;
      const details = document.createElement("span");
      details.className = "details";
      const where = v.position ? [] : [_("no position yet")];
      const offline = v.collector.online ? [] : [_("collector offline")];
      details.textContent = [takeover, leg, ...where, ...offline].join(" · ");
      // Its visible text is its name, so speech control finds it by what is shown.
      b.append(dot, name, " ", modeWord, " ", details);
      b.title = _("%(vehicle)s: open its cockpit", { vehicle: v.vehicle.name });
      b.addEventListener("click", () => this.open(v));
      const li = document.createElement("li");
      li.append(b);
      return li;
    }));
  },

  /* The durations grow between reads. */
  tick() {
    if (this.visible() && this.vehicles.length) this.renderList();
  },

  /* The vehicle's cockpit: its test event, shift and leg, as a shared link would give. */
  async open(v) {
    state.selected.event = v.leg.test_event;
    state.selected.shift = v.leg.shift;
    state.selected.leg = v.leg.id;
    state.segment = null;
    await this.show(false);
    await loadLevel("event");
  },
};

/* Back and Forward between the fleet and a cockpit opened from it. */
window.addEventListener("popstate", async () => {
  const q = new URLSearchParams(location.search);
  const fleet = q.get("view") === "fleet";
  try {
    if (fleet) return await Fleet.show(true, { fromHistory: true });
    for (const k of ["event", "shift", "leg"]) state.selected[k] = /^\d+$/.test(q.get(k) || "") ? Number(q.get(k)) : null;
    await Fleet.show(false, { fromHistory: true });
    await loadLevel("event");
  } catch (err) {
    showError(err);
  }
});

$("#toggle-fleet")?.addEventListener("click", () => Fleet.show(!Fleet.visible()).catch(showError));
$("#fleet-fit")?.addEventListener("click", () => Fleet.fitAll());
