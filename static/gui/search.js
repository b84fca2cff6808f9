/* "Where did it fail" on the comparison page: an area drawn as a rectangle (two
 * clicks on the map) or a test case's area, the filters, and the take-overs
 * found by the server (GET /api/segments/found/) on the map, in a list and as
 * GeoJSON and CSV downloads.  The server decides what lies inside.  Leaflet.markercluster
 * (global L.markerClusterGroup, a deferred script like Leaflet) groups them. */
import { CONFIG, $, element } from "./dom.js";
import { api, csrfToken, list, plainMessage } from "./api.js";
import { plainMap } from "./comparemap.js";
import { _, plural } from "./i18n.js";

const SHOWN_IN_LIST = 200; // the downloads hold every take-over found

const search = { map: null, area: null, outline: null, corner: null, drawing: false, found: null, cases: [], downloaded: null };

function say(text, isError = false) {
  const line = $("#search-status");
  line.textContent = text;
  line.classList.toggle("error", isError);
}

function fill(select, rows) {
  select.append(...rows.map(([value, text]) => new Option(text, value)));
}

/* The area as a GeoJSON polygon, for the server's `within`. */
function boxPolygon(a, b) {
  const [w, e] = [Math.min(a.lng, b.lng), Math.max(a.lng, b.lng)];
  const [s, n] = [Math.min(a.lat, b.lat), Math.max(a.lat, b.lat)];
  return { type: "Polygon", coordinates: [[[w, s], [e, s], [e, n], [w, n], [w, s]]] };
}

function showArea(geometry) {
  search.area = geometry;
  if (search.outline) search.outline.remove();
  search.outline = L.geoJSON(geometry, { style: { color: "#1f5fbf", weight: 2, fillOpacity: 0.08 }, interactive: false }).addTo(search.map);
  // At once, not animated: a corner clicked while the map still zooms would be lost.
  search.map.fitBounds(search.outline.getBounds(), { maxZoom: 18, animate: false });
}

function startDrawing() {
  search.drawing = true;
  search.corner = null;
  // Two corners tapped in quick succession are not a double tap that zooms.
  search.map.doubleClickZoom.disable();
  $("#search-map").classList.add("drawing");
  say(_("Click the first corner of the area on the map."));
}

function mapClicked(e) {
  if (!search.drawing) return;
  if (!search.corner) {
    search.corner = e.latlng;
    say(_("Click the opposite corner."));
    return;
  }
  search.drawing = false;
  search.map.doubleClickZoom.enable();
  $("#search-map").classList.remove("drawing");
  $("#search-form").elements.case_area.value = "";
  showArea(boxPolygon(search.corner, e.latlng));
  say(_("Area drawn. Press Search."));
}

function query() {
  const form = $("#search-form").elements;
  const q = new URLSearchParams({ master: "true", mode: "ito" });
  for (const name of ["reason", "vehicle", "test_event"]) if (form[name].value) q.set(name, form[name].value);
  if (form.start_after.value) q.set("start_after", `${form.start_after.value}T00:00:00Z`);
  if (form.start_before.value) {
    // "Until" includes the day: before the next day's midnight (UTC).
    const next = new Date(`${form.start_before.value}T00:00:00Z`);
    next.setUTCDate(next.getUTCDate() + 1);
    q.set("start_before", next.toISOString());
  }
  if (search.area) q.set("within", JSON.stringify(search.area));
  return q;
}

function cockpitLink(f) {
  const p = f.properties;
  const q = new URLSearchParams({ event: p.test_event, shift: p.shift, leg: p.leg, segment: f.id });
  return `/?${q}`;
}

function showFound(collection) {
  if (search.found) search.found.remove();
  const features = collection.features.filter((f) => f.geometry);
  // Thousands of take-overs as clusters with their count (Leaflet.markercluster);
  // a cluster opens as the map zooms in, down to the single circles.
  const points = L.geoJSON({ type: "FeatureCollection", features }, {
    pointToLayer: (f, at) => L.circleMarker(at, { radius: 6, color: "#b00020", weight: 1, fillOpacity: 0.7 }),
    onEachFeature: (f, layer) => layer.bindTooltip(element("span", { textContent: f.properties.label || "" })),
  });
  search.found = L.markerClusterGroup({ chunkedLoading: true, showCoverageOnHover: false });
  search.found.addLayer(points);
  search.map.addLayer(search.found);
  // Without an area the map would stay where it was: show where the take-overs are.
  if (!search.area && features.length) search.map.fitBounds(points.getBounds(), { maxZoom: 18, animate: false });
  const items = collection.features.slice(0, SHOWN_IN_LIST).map((f) => {
    const p = f.properties;
    const where = `#${p.test_event}${p.test_event_location ? ` ${p.test_event_location}` : ""}`;
    const text = `${where} · ${p.label} · ${(p.start || "").slice(0, 16).replace("T", " ")} · ${p.vehicle}${p.reason ? ` · ${p.reason}` : ""}`;
    return element("li", {}, [element("a", { href: cockpitLink(f), textContent: text })]);
  });
  $("#search-results").replaceChildren(...items);
  const n = collection.features.length;
  const more = n > SHOWN_IN_LIST ? " " + _("The list shows the first %(count)s; the downloads hold all.", { count: SHOWN_IN_LIST }) : "";
  say(plural(ngettext("%(count)s take-over found.", "%(count)s take-overs found.", n), n) + more);
}

/* Sent by POST: a test case's area of thousands of vertices does not fit in an address. */
async function runSearch(e) {
  e.preventDefault();
  const q = query();
  say(_("Searching…"));
  try {
    const found = await api("POST", "segments/found/", { ...Object.fromEntries(q), as: "geojson" });
    showFound(found);
    search.downloaded = q;
    // The address of each download, to copy; a click sends the search by POST.
    $("#search-geojson").href = `${CONFIG.apiRoot}segments/found/?${q}&as=geojson`;
    $("#search-csv").href = `${CONFIG.apiRoot}segments/found/?${q}&as=csv`;
    $("#search-downloads").hidden = false;
  } catch (err) {
    say(plainMessage(err), true);
  }
}

/* The file of the search shown, by a form's POST (the answer is an attachment). */
function download(e, kind) {
  e.preventDefault();
  const fields = [...search.downloaded, ["as", kind], ["csrfmiddlewaretoken", csrfToken()]];
  const form = element("form", { method: "post", action: `${CONFIG.apiRoot}segments/found/` }, fields.map(([name, value]) => element("input", { type: "hidden", name, value })));
  document.body.append(form);
  form.submit();
  form.remove();
}

function caseChosen(e) {
  const chosen = search.cases.find((c) => String(c.id) === e.target.value);
  if (chosen) showArea(chosen.area);
}

async function main() {
  search.map = plainMap($("#search-map"), { canvas: true });
  search.map.on("click", mapClicked);
  $("#search-draw").addEventListener("click", startDrawing);
  $("#search-form").addEventListener("submit", runSearch);
  $("#search-geojson").addEventListener("click", (e) => download(e, "geojson"));
  $("#search-csv").addEventListener("click", (e) => download(e, "csv"));
  const form = $("#search-form").elements;
  form.case_area.addEventListener("change", caseChosen);
  try {
    const [reasons, vehicles, events, areas] = await Promise.all([
      list("ito-reasons/"),
      list("vehicles/"),
      list("test-events/"),
      api("GET", "test-case-areas/", undefined, { root: CONFIG.guiApiRoot }),
    ]);
    fill(form.reason, reasons.map((r) => [r.key, r.label]));
    fill(form.vehicle, vehicles.map((v) => [v.id, v.short_description]));
    fill(form.test_event, events.map((t) => [t.id, `#${t.id} ${t.location || ""}`]));
    search.cases = areas.cases;
    fill(form.case_area, areas.cases.map((c) => [c.id, `#${c.test_event} ${c.key}: ${c.title}`]));
  } catch (err) {
    say(plainMessage(err), true);
  }
}


if ($("#search-map")) main();
