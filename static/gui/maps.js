/* Map drawing for the FTT GUI: a GPS map (tiles optional) and a local map in
 * map-frame metres.  Tracks are polylines that grow point by point, so live
 * updates never redraw what is already on screen.  Leaflet is the page's global
 * L (django-leaflet's static files, loaded before the modules). */
import { element } from "./dom.js";
import { _ } from "./i18n.js";

const COLORS = { auto: "#1a9c3a", ito: "#d22020", selected: "#1f5fbf" };
// A fix older than this, and the robot's marker is greyed: where it was, not where it is.
const FIX_FRESH_S = 5;

/* An image placed by three corners (top-left, top-right, bottom-left), so it
 * can be rotated and scaled; Leaflet's own imageOverlay only takes a box. */
const AffineImage = L.Layer.extend({
  initialize(url, corners, options) {
    this._url = url;
    this._corners = corners;
    L.setOptions(this, options);
  },
  onAdd(map) {
    this._img = L.DomUtil.create("img", "leaflet-zoom-hide ftt-affine");
    this._img.alt = this.options.alt ?? "";
    this._img.style.position = "absolute";
    this._img.style.transformOrigin = "0 0";
    this._img.style.opacity = this.options.opacity ?? 1;
    this._img.style.pointerEvents = "none";
    this._img.onload = () => this._update();
    this._img.src = this._url;
    map.getPanes().overlayPane.appendChild(this._img);
    map.on("zoomend viewreset moveend", this._update, this);
    this._update();
  },
  onRemove(map) {
    L.DomUtil.remove(this._img);
    map.off("zoomend viewreset moveend", this._update, this);
  },
  setImage(url, corners) {
    this._corners = corners;
    if (this._img && this._url !== url) this._img.src = url;
    this._url = url;
    this._update();
  },
  _update() {
    if (!this._map || !this._img || !this._img.naturalWidth) return;
    const p = (c) => this._map.latLngToLayerPoint(c);
    const tl = p(this._corners.topLeft), tr = p(this._corners.topRight), bl = p(this._corners.bottomLeft);
    const w = this._img.naturalWidth, h = this._img.naturalHeight;
    const m = [(tr.x - tl.x) / w, (tr.y - tl.y) / w, (bl.x - tl.x) / h, (bl.y - tl.y) / h, tl.x, tl.y];
    this._img.style.left = "0px";
    this._img.style.top = "0px";
    this._img.style.transform = `matrix(${m.join(",")})`;
  },
});

/* Zoomed in this far beyond the zoom the tracks were thinned for, the thinned
 * line is a pixel off: the area in view is fetched in detail. */
const DETAIL_AFTER_ZOOMS = 1;
// Panning and zooming settle for this long before the detail is asked for.
const DETAIL_DELAY_MS = 250;

class TrackMap {
  /* toLatLngs turns stored points into positions Leaflet takes for this map. */
  constructor(element, options, toLatLngs) {
    this.element = element;
    this.map = L.map(element, options);
    this.toLatLngs = toLatLngs;
    // One canvas for every track and take-over: a polyline of thousands of
    // points is one SVG path the browser lays out again on every change.
    this.renderer = L.canvas({ padding: 0.5 });
    this.renderer.on("update", () => this.markDrawn());
    this.tracks = new Map(); // master segment id -> {line, mode, overview, live}
    this.markers = L.layerGroup().addTo(this.map);
    this.selectedId = null;
    this.fitted = false;
    this.follow = false; // pan to each new point of the vehicle
    this.labelOf = (id) => _("Segment %(id)s", { id });
    this.overviewZoom = null; // the zoom the server thinned the whole tracks for
    this.detail = null; // {zoom, controller, shown}: the area in view in detail
  }
  clear() {
    for (const t of this.tracks.values()) t.line.remove();
    this.tracks.clear();
    this.markers.clearLayers();
    if (this.robot) this.robot.remove();
    this.robot = null;
    this.robotFix = null;
    this.element.dataset.robot = "";
    this.takeOvers = null;
    this.fitted = false;
    this.dropDetail();
    this.markDrawn();
  }
  style(id, mode) {
    const selected = id === this.selectedId;
    return { color: selected ? COLORS.selected : COLORS[mode] || "#666", weight: selected ? 6 : 3, opacity: 0.9, renderer: this.renderer };
  }
  /* The whole track as the server thinned it for this.overviewZoom. */
  setTrack(id, mode, points) {
    let t = this.tracks.get(id);
    if (!t) {
      const line = L.polyline(this.toLatLngs(points), this.style(id, mode)).addTo(this.map);
      line.bindTooltip(() => element("span", { textContent: `${this.labelOf(id)} (${mode.toUpperCase()})` }));
      t = { line, mode, overview: points.slice(), live: [] };
      this.tracks.set(id, t);
    } else {
      t.overview = points.slice();
      t.line.setLatLngs(this.toLatLngs(points));
    }
    this.markDrawn();
    if (this.detail) {
      // The new overview replaced this line's detail: fetch it again.
      this.detail.controller.abort();
      this.detail = null;
      this.scheduleDetail();
    }
    return t;
  }
  appendPoints(id, mode, points) {
    const t = this.tracks.get(id) || this.setTrack(id, mode, []);
    t.overview.push(...points);
    // A detail answer on its way was read before these points: they follow it.
    if (this.detail && !this.detail.shown) t.live.push(...points);
    // One redraw per batch: each addLatLng would project the whole line again.
    if (points.length) t.line.setLatLngs(t.line.getLatLngs().concat(this.toLatLngs(points)));
    this.markDrawn();
    if (!this.fitted) this.fitAll();
    else if (this.follow && points.length) this.map.panTo(this.toLatLngs(points.slice(-1))[0]);
  }
  /* The robot now: a dot at `point` (the map's own order), an arrow where its heading
   * (radians, counter-clockwise from east) is known; `fixedAt` is when the page heard
   * the fix (Date.now()), null when it does not know, as after a reload. */
  setRobot(point, heading = null, fixedAt = null) {
    const at = this.toLatLngs([point])[0];
    if (!this.robot) {
      this.robot = L.marker(at, { interactive: false, keyboard: false, zIndexOffset: 1000 }).addTo(this.map);
    } else this.robot.setLatLng(at);
    if (heading !== this.robotHeading || !this.robot.getIcon().options.html) {
      this.robotHeading = heading;
      // Screen angles turn clockwise; the arrow is drawn pointing east.
      const arrow = heading === null ? "" : `<span class="robot-heading" style="transform: rotate(${(-heading * 180) / Math.PI}deg)"></span>`;
      this.robot.setIcon(L.divIcon({ className: "robot-marker", html: `<span class="robot-dot"></span>${arrow}`, iconSize: [22, 22] }));
    }
    if (fixedAt !== null) this.robotFix = fixedAt;
    this.tickRobot();
  }
  /* Called every second: greys the marker once its fix is old. */
  tickRobot() {
    if (!this.robot) return;
    const fresh = this.robotFix !== null && (Date.now() - this.robotFix) / 1000 <= FIX_FRESH_S;
    const el = this.robot.getElement();
    if (el) el.classList.toggle("stale", !fresh);
    this.element.dataset.robot = fresh ? "fresh" : "stale";
  }
  /* spots: [[segment id, point], ...]; the same spots again leave the canvas as it is. */
  setTakeOvers(spots) {
    // Only circles that are new, moved or gone change: a new take-over on a long
    // leg adds one circle instead of drawing them all again.
    const kept = this.takeOvers || new Map(); // segment id -> {key, circle}
    const now = new Map();
    let changed = false;
    for (const [id, point] of spots) {
      const key = String(point);
      let spot = kept.get(id);
      if (spot && spot.key !== key) {
        spot.circle.setLatLng(this.toLatLngs([point])[0]);
        spot.key = key;
        changed = true;
      } else if (!spot) {
        const circle = L.circleMarker(this.toLatLngs([point])[0], { radius: 7, color: COLORS.ito, weight: 2, fillOpacity: 0.2, renderer: this.renderer })
          .bindTooltip(() => element("span", { textContent: _("Take-over, %(segment)s", { segment: this.labelOf(id) }) }))
          .addTo(this.markers);
        spot = { key, circle };
        changed = true;
      }
      now.set(id, spot);
      kept.delete(id);
    }
    for (const gone of kept.values()) {
      this.markers.removeLayer(gone.circle);
      changed = true;
    }
    this.takeOvers = now;
    if (changed) this.markDrawn();
  }
  /* What the canvas shows, on the map element for tests and benchmarks:
   * tracks, their points, take-overs, the detail zoom and when it was drawn.
   * Set in an animation frame requested after the renderer's own, so it
   * runs once the canvas holds these lines. */
  markDrawn() {
    if (this.markPending) return;
    this.markPending = true;
    requestAnimationFrame(() => {
      this.markPending = false;
      let lines = 0, points = 0;
      for (const t of this.tracks.values()) {
        const n = t.line.getLatLngs().length;
        if (n) lines += 1;
        points += n;
      }
      const d = this.element.dataset;
      d.tracks = lines;
      d.trackPoints = points;
      d.takeOvers = this.markers.getLayers().length;
      d.detailZoom = this.detail && this.detail.shown ? this.detail.zoom : "";
      d.drawnAt = Math.round(performance.now());
    });
  }
  /* load(bbox, zoom, signal) answers {segment id: points} for the area in
   * view, finer inside bbox ([xmin, ymin, xmax, ymax] in the map's own
   * coordinates).  It runs after the map settles zoomed in beyond the
   * overview; zoomed back out, the overview lines return.  A failed load
   * leaves the overview and goes to onError. */
  followView(load, onError) {
    this.detailLoader = load;
    this.detailError = onError;
    this.map.on("moveend", () => this.scheduleDetail());
  }
  scheduleDetail() {
    clearTimeout(this.viewTimer);
    this.viewTimer = setTimeout(() => this.viewChanged().catch((err) => {
      this.dropDetail();
      this.detailError(err);
    }), DETAIL_DELAY_MS);
  }
  dropDetail() {
    if (!this.detail) return;
    this.detail.controller.abort();
    if (this.detail.shown) {
      for (const t of this.tracks.values()) t.line.setLatLngs(this.toLatLngs(t.overview));
    }
    this.detail = null;
    this.markDrawn();
  }
  async viewChanged() {
    const zoom = this.map.getZoom();
    if (!this.detailLoader || this.overviewZoom === null || zoom < this.overviewZoom + DETAIL_AFTER_ZOOMS || !this.tracks.size) {
      this.dropDetail();
      return;
    }
    const previous = this.detail;
    if (previous) previous.controller.abort();
    const detail = { zoom: Math.ceil(zoom), controller: new AbortController(), shown: false };
    this.detail = detail;
    for (const t of this.tracks.values()) t.live = [];
    const b = this.map.getBounds().pad(0.25);
    const bbox = [b.getWest(), b.getSouth(), b.getEast(), b.getNorth()];
    let pieces;
    try {
      pieces = await this.detailLoader(bbox, detail.zoom, detail.controller.signal);
    } catch (err) {
      if (err.name === "AbortError") return;
      throw err;
    }
    if (this.detail !== detail) return;
    for (const [id, points] of Object.entries(pieces)) {
      const t = this.tracks.get(Number(id));
      if (t) t.line.setLatLngs(this.toLatLngs(points.concat(t.live)));
    }
    detail.shown = true;
    this.markDrawn();
  }
  select(id) {
    const previous = this.selectedId;
    this.selectedId = id;
    for (const key of [previous, id]) {
      const t = this.tracks.get(key);
      if (t) t.line.setStyle(this.style(key, t.mode));
    }
    const t = this.tracks.get(id);
    if (t && t.line.getLatLngs().length) {
      t.line.bringToFront();
      this.map.fitBounds(t.line.getBounds(), { maxZoom: this.maxFocusZoom, padding: [30, 30] });
    }
  }
  fitAll(options = {}) {
    let bounds = null;
    for (const t of this.tracks.values()) {
      if (!t.line.getLatLngs().length) continue;
      bounds = bounds ? bounds.extend(t.line.getBounds()) : L.latLngBounds(t.line.getBounds().getSouthWest(), t.line.getBounds().getNorthEast());
    }
    if (bounds) {
      this.map.fitBounds(bounds, { maxZoom: this.maxFocusZoom, padding: [20, 20], ...options });
      this.fitted = true;
    }
  }
  invalidate() { this.map.invalidateSize(); }
}

class GpsMap extends TrackMap {
  constructor(element, messageElement) {
    // Points come as [lat, lon], which Leaflet takes as they are.
    super(element, { center: [50.6, 7.2], zoom: 3, maxZoom: 21, zoomControl: true }, (points) => points);
    this.maxFocusZoom = 19;
    this.messageElement = messageElement;
    this.tileLayer = null;
    this.overlay = null;
    this.layers = L.control.layers(null, null, { collapsed: true });
    // The site's tile server is asked only once the basemaps are known: when the
    // event starts on an offline layer, nothing goes to the internet.
    this.basemapsKnown = false;
    this.chosenBasemap = null;
  }
  setTiles(url, attribution) {
    if (this.tileLayer) this.tileLayer.remove();
    this.tileLayer = null;
    this.tilesLoaded = 0;
    this.tileErrors = 0;
    if (!url) {
      this.noTiles(_("No tile server is set: the map shows tracks on a plain background."));
      return;
    }
    this.element.classList.remove("no-tiles");
    this.messageElement.hidden = true;
    // OpenStreetMap's tile policy asks for this credit on every map.
    const credit = attribution || (url.includes("openstreetmap") ? "© OpenStreetMap contributors" : "");
    this.tileLayer = L.tileLayer(url, { maxZoom: 21, maxNativeZoom: 19, attribution: credit });
    this.tileLayer.on("tileload", () => {
      this.tilesLoaded += 1;
      this.element.classList.remove("no-tiles");
      this.messageElement.hidden = true;
    });
    this.tileLayer.on("tileerror", () => {
      this.tileErrors += 1;
      if (!this.tilesLoaded) this.noTiles(_("Map tiles are unavailable (the tile server cannot be reached). Tracks are still shown on a plain background."));
    });
    if (this.basemapsKnown && !this.chosenBasemap) this.tileLayer.addTo(this.map);
    if (this.basemapsKnown && this.basemaps.length) this.layers.addBaseLayer(this.tileLayer, _("Tile server"));
  }
  /* The layer switcher: FTT's own basemaps, which work offline, next to the
   * site's tile server; the test event's default basemap starts selected.
   * One control holds the base layers and the local-map overlay. */
  setBasemaps(specs) {
    for (const layer of this.basemaps || []) {
      this.layers.removeLayer(layer);
      layer.remove();
    }
    if (this.tileLayer) this.layers.removeLayer(this.tileLayer);
    this.basemaps = [];
    this.basemapsKnown = true;
    this.chosenBasemap = null;
    if (!specs.length) {
      this.tileLayer?.addTo(this.map);
      return;
    }
    let chosen = null;
    for (const spec of specs) {
      const options = { attribution: spec.attribution, minZoom: spec.minZoom, maxZoom: 21, maxNativeZoom: spec.maxZoom };
      if (spec.bounds) options.bounds = spec.bounds;
      const layer = L.tileLayer(spec.url, options);
      layer.on("tileload", () => {
        this.element.classList.remove("no-tiles");
        this.messageElement.hidden = true;
      });
      this.layers.addBaseLayer(layer, spec.name);
      this.basemaps.push(layer);
      if (spec.default) chosen = layer;
    }
    if (this.tileLayer) this.layers.addBaseLayer(this.tileLayer, _("Tile server"));
    this.layers.addTo(this.map);
    this.chosenBasemap = chosen;
    if (chosen) {
      if (this.tileLayer) this.tileLayer.remove();
      chosen.addTo(this.map);
    } else this.tileLayer?.addTo(this.map);
  }
  noTiles(message) {
    this.element.classList.add("no-tiles");
    this.messageElement.textContent = message;
    this.messageElement.hidden = false;
  }
  setOverlay(url, corners) {
    const c = { topLeft: corners.top_left, topRight: corners.top_right, bottomLeft: corners.bottom_left };
    if (this.overlay) {
      this.overlay.setImage(url, c);
      return;
    }
    this.overlay = new AffineImage(url, c, { opacity: 0.45, alt: _("Robot's local map over the GPS map") });
    this.layers.addOverlay(this.overlay, _("Local map"));
    this.layers.addTo(this.map);
  }
  removeOverlay() {
    if (!this.overlay) return;
    this.layers.removeLayer(this.overlay);
    this.overlay.remove();
    this.overlay = null;
    this.layers.remove();
  }
}

class LocalMap extends TrackMap {
  constructor(element) {
    // Map-frame metres: Leaflet's "lat" is y and "lng" is x.
    super(element, { crs: L.CRS.Simple, center: [0, 0], zoom: 2, minZoom: -5, maxZoom: 8, zoomSnap: 0.25 }, (points) => points.map((p) => [p[1], p[0]]));
    this.maxFocusZoom = 6;
    this.image = null;
  }
  setMapImage(info) {
    const corner = (xy) => L.latLng(xy[1], xy[0]);
    const c = { topLeft: corner(info.corners.top_left), topRight: corner(info.corners.top_right), bottomLeft: corner(info.corners.bottom_left) };
    if (this.image) this.image.setImage(info.url, c);
    else {
      this.image = new AffineImage(info.url, c, { opacity: 0.9, alt: "Robot's local map" }).addTo(this.map);
    }
    if (!this.fitted) {
      const b = L.latLngBounds([c.topLeft, c.topRight, c.bottomLeft]);
      this.map.fitBounds(b);
    }
  }
  removeMapImage() {
    if (this.image) this.image.remove();
    this.image = null;
  }
}

export { COLORS, GpsMap, LocalMap };
