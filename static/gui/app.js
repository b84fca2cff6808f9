/* FTT operator GUI.  Every change goes through the REST API (/api/), which
 * applies the rules; this script only shows state and forwards clicks.  Live
 * updates arrive on the websocket ws/live/ (see docs/gui.md). */
"use strict";

const CONFIG = JSON.parse(document.getElementById("gui-config").textContent);
const $ = (sel, root = document) => root.querySelector(sel);
const $$ = (sel, root = document) => Array.from(root.querySelectorAll(sel));

/* ---------------------------------------------------------------- errors -- */

const NETWORK_MESSAGE = "The server cannot be reached. Check the network connection and try again.";

class ApiError extends Error {
  constructor(message, status, errors) {
    super(message);
    this.status = status;
    this.errors = errors || {};
  }
}

function plainMessage(error) {
  if (error instanceof ApiError) return error.message;
  if (error instanceof TypeError) return NETWORK_MESSAGE;
  return "Something went wrong: " + (error && error.message ? error.message : String(error));
}

function showError(error, where) {
  // Inside a dialog, field errors go next to their fields; the rest to the dialog's box.
  if (where && error instanceof ApiError && showFieldErrors(error, where.closest("dialog"))) {
    where.textContent = "Please correct the marked fields.";
    where.hidden = false;
    where.scrollIntoView({ block: "nearest" });
    return;
  }
  const box = where || $("#error");
  const text = plainMessage(error);
  if (box.id === "error") {
    $(".text", box).textContent = text;
  } else {
    box.textContent = text;
    box.scrollIntoView({ block: "nearest" });
  }
  box.hidden = false;
}

/* Puts each server message under the field it names, in the field's own label. */
function showFieldErrors(error, dialog) {
  if (!dialog) return false;
  $$(".field-error", dialog).forEach((el) => el.remove());
  let shown = 0;
  for (const [field, messages] of Object.entries(error.errors || {})) {
    const input = dialog.querySelector(`[name="${CSS.escape(field)}"]`);
    if (!input) continue;
    const p = document.createElement("p");
    p.className = "field-error error";
    p.id = `error-${field}`;
    const label = input.closest("label");
    const name = label ? label.firstChild.textContent.trim() : field;
    p.textContent = `${name}: ${[].concat(messages).join(" ")}`;
    input.setAttribute("aria-invalid", "true");
    input.setAttribute("aria-describedby", p.id);
    input.after(p);
    if (!shown) input.focus();
    shown += 1;
  }
  return shown > 0;
}

function clearError(where) {
  const box = where || $("#error");
  box.hidden = true;
  const dialog = where && where.closest("dialog");
  if (dialog) {
    $$(".field-error", dialog).forEach((el) => el.remove());
    $$("[aria-invalid]", dialog).forEach((el) => el.removeAttribute("aria-invalid"));
  }
}

$("#error .dismiss").addEventListener("click", () => clearError());

function notice(text) {
  const box = $("#notice");
  box.textContent = text;
  box.hidden = false;
  clearTimeout(notice.timer);
  notice.timer = setTimeout(() => (box.hidden = true), 4000);
}

/* ------------------------------------------------------------------- API -- */

function csrfToken() {
  const match = document.cookie.match(/(?:^|;\s*)csrftoken=([^;]+)/);
  return match ? decodeURIComponent(match[1]) : "";
}

const STATUS_WORDS = {
  401: "You are signed out. Reload the page and sign in again.",
  403: "Your account may not do this. Ask an administrator for the operator role.",
  404: "This entry no longer exists; somebody may have deleted it.",
  413: "The file is too large for the server.",
  500: "The server failed to do this. Please try again; if it keeps failing, tell the administrator.",
  502: NETWORK_MESSAGE,
  503: NETWORK_MESSAGE,
};

/* "Text: This field may not be blank." rather than a bare message without its field. */
function describeErrors(data) {
  const parts = [];
  for (const [field, messages] of Object.entries(data.errors || {})) {
    for (const m of [].concat(messages)) {
      if (field === "non_field_errors" || field === "detail") parts.push(String(m));
      else {
        const name = field.replace(/_/g, " ");
        parts.push(`${name.charAt(0).toUpperCase()}${name.slice(1)}: ${m}`);
      }
    }
  }
  return parts.length ? parts.join(" ") : data.detail;
}

async function api(method, path, body, { root = CONFIG.apiRoot } = {}) {
  const headers = { Accept: "application/json" };
  let payload;
  if (body instanceof FormData) {
    payload = body;
  } else if (body !== undefined) {
    headers["Content-Type"] = "application/json";
    payload = JSON.stringify(body);
  }
  if (method !== "GET") headers["X-CSRFToken"] = csrfToken();
  const response = await fetch(root + path, { method, headers, body: payload, credentials: "same-origin" });
  if (response.status === 204) return null;
  let data = null;
  const type = response.headers.get("Content-Type") || "";
  if (type.includes("json")) data = await response.json().catch(() => null);
  if (!response.ok) {
    let message = data && data.detail ? describeErrors(data) : STATUS_WORDS[response.status];
    if (!message) message = `The server refused this (error ${response.status}).`;
    throw new ApiError(message, response.status, data && data.errors);
  }
  return data;
}

async function list(path, params = {}) {
  const query = new URLSearchParams({ page_size: "5000", ...params });
  const data = await api("GET", `${path}?${query}`);
  return Array.isArray(data) ? data : data.results;
}

/* ----------------------------------------------------------------- state -- */

const LEVELS = {
  event: { path: "test-events/", label: "test event", parent: null, child: "shift" },
  shift: { path: "shifts/", label: "shift", parent: "event", parentField: "test_event", child: "leg" },
  leg: { path: "legs/", label: "leg", parent: "shift", parentField: "shift", child: null },
};

/* Event, shift, leg and segment live in the address, so reload and shared links restore them. */
const fromUrl = (() => {
  const q = new URLSearchParams(location.search);
  const n = (k) => (/^\d+$/.test(q.get(k) || "") ? Number(q.get(k)) : null);
  return { event: n("event"), shift: n("shift"), leg: n("leg"), segment: n("segment") };
})();

function saveUrl() {
  const q = new URLSearchParams();
  for (const k of ["event", "shift", "leg"]) if (state.selected[k]) q.set(k, state.selected[k]);
  if (state.segment) q.set("segment", state.segment);
  const next = q.toString() ? `?${q}` : location.pathname;
  if (next !== location.search) history.replaceState(null, "", next || location.pathname);
}

const state = {
  rows: { event: [], shift: [], leg: [] },
  selected: { event: fromUrl.event, shift: fromUrl.shift, leg: fromUrl.leg },
  segments: [],
  tracks: {},
  labels: {}, // segment id -> "Leg 2 · #7", from the server
  shownLeg: undefined, // leg whose segments and tracks are drawn
  basemapsOf: undefined, // test event whose basemaps the switcher offers
  segment: null, // selected segment id
  catalogue: {},
  lastEventId: null,
};

/* Times are shown in the selected test event's time zone, as the model says. */
function zoneOptions() {
  const event = byId(state.rows.event, state.selected.event);
  return event && event.time_zone ? { timeZone: event.time_zone, timeZoneName: "short" } : {};
}
function fmtTime(iso, options = {}) {
  if (!iso) return "—";
  try {
    return new Date(iso).toLocaleString(undefined, { ...zoneOptions(), ...options });
  } catch {
    return new Date(iso).toLocaleString(undefined, options);
  }
}
/* Time of day only: in the segment list the date is the leg's and would push
   duration and distance out of sight on a laptop; the full time is the title. */
const CLOCK = { hour: "2-digit", minute: "2-digit", second: "2-digit", hourCycle: "h23", timeZoneName: undefined };
const fmtClock = (iso) => fmtTime(iso, CLOCK);
const fmtDay = (iso) => (iso ? new Date(iso).toLocaleDateString() : "");

function fmtDuration(start, end) {
  const seconds = Math.max(0, ((end ? new Date(end) : new Date()) - new Date(start)) / 1000);
  const h = Math.floor(seconds / 3600), m = Math.floor((seconds % 3600) / 60), s = Math.floor(seconds % 60);
  return h ? `${h} h ${m} min` : m ? `${m} min ${s} s` : `${s} s`;
}

function fmtDistance(metres) {
  if (metres === null || metres === undefined) return "—";
  return metres >= 1000 ? `${(metres / 1000).toFixed(2)} km` : `${metres.toFixed(1)} m`;
}

function rowLabel(level, row) {
  const status = row.is_open ? "open" : "closed";
  if (level === "event") return `#${row.id} ${row.location || "(no location)"} · ${fmtDay(row.start)} · ${status}`;
  if (level === "shift") return `Shift ${row.number} · ${vehicleName(row.vehicle)} · ${fmtTime(row.start)} · ${status}`;
  return `Leg ${row.number} · ${fmtTime(row.start)} · ${status}`;
}

const byId = (rows, id) => rows.find((r) => r.id === id) || null;
const current = (level) => byId(state.rows[level], state.selected[level]);
const vehicleName = (id) => (byId(state.catalogue.vehicles || [], id) || {}).short_description || `vehicle ${id}`;
const segmentLabel = (id) => state.labels[id] || `segment ${id}`;
const shortLabel = (id) => (state.labels[id] || "").replace(/^Leg \d+ · /, "") || "…";
const reasonName = (key) => {
  const r = (state.catalogue.reasons || []).find((x) => x.key === key);
  return r ? r.short_description : key || "";
};

/* --------------------------------------------------------------- pickers -- */

async function loadCatalogues() {
  const [reasons, weather, poseSources, vehicles, performers, personnel] = await Promise.all([
    list("ito-reasons/"), list("weather/"), list("pose-sources/"), list("vehicles/"),
    list("performers/"), list("personnel/"),
  ]);
  Object.assign(state.catalogue, { reasons, weather, poseSources, vehicles, performers, personnel });
  const any = $("#reason-any");
  any.replaceChildren(...reasons.map((r) => new Option(r.short_description, r.key)));
}

async function loadLevel(level, keepSelection = true) {
  const info = LEVELS[level];
  const select = $(`#pick-${level}`);
  let rows = [];
  if (!info.parent) rows = await list(info.path);
  else if (state.selected[info.parent]) rows = await list(info.path, { [info.parentField]: state.selected[info.parent] });
  // Newest first, whatever order the server uses.
  rows.sort((a, b) => (a.start < b.start ? 1 : a.start > b.start ? -1 : b.id - a.id));
  state.rows[level] = rows;
  let chosen = keepSelection && byId(rows, state.selected[level]) ? state.selected[level] : null;
  if (chosen === null && rows.length === 1) chosen = rows[0].id; // one child: take it
  const placeholder = new Option(rows.length ? `— choose a ${info.label} —` : `no ${info.label} yet`, "");
  select.replaceChildren(placeholder, ...rows.map((r) => {
    const o = new Option(rowLabel(level, r), r.id);
    o.className = r.is_open ? "open-log" : "closed-log";
    return o;
  }));
  select.value = chosen === null ? "" : String(chosen);
  const changed = chosen !== state.selected[level];
  state.selected[level] = chosen;
  updateLevelState(level);
  saveUrl();
  if (info.child) await loadLevel(info.child, keepSelection && !changed);
  else if (state.selected.leg !== state.shownLeg) await selectionChanged();
  else {
    // Same leg as before: only the labels and states changed, keep the drawing.
    Live.subscribe();
    Collector.refresh();
  }
}

function updateLevelState(level) {
  const row = current(level);
  const badge = $(`[data-state="${level}"]`);
  badge.textContent = row ? (row.is_open ? "open" : "closed") : "";
  badge.className = "state" + (row ? (row.is_open ? " open" : " closed") : "");
  const parentRow = LEVELS[level].parent ? current(LEVELS[level].parent) : true;
  const can = CONFIG.canOperate;
  const setBtn = (action, enabled, show = true) => {
    const b = $(`[data-action="${action}"][data-level="${level}"]`);
    if (!b) return;
    b.hidden = !show;
    // Viewers may open Edit to read every field; the dialog is read-only for them.
    b.disabled = (action !== "edit" && !can) || !enabled;
  };
  setBtn("new", Boolean(parentRow));
  setBtn("edit", Boolean(row));
  setBtn("delete", Boolean(row));
  const reopen = level === "event" && row && !row.is_open;
  setBtn("end", Boolean(row && row.is_open), !reopen);
  setBtn("reopen", Boolean(reopen), Boolean(reopen));
}

for (const level of Object.keys(LEVELS)) {
  $(`#pick-${level}`).addEventListener("change", async (e) => {
    state.selected[level] = e.target.value ? Number(e.target.value) : null;
    updateLevelState(level);
    saveUrl();
    try {
      const child = LEVELS[level].child;
      if (child) {
        state.selected[child] = null;
        await loadLevel(child, false);
      } else await selectionChanged();
    } catch (err) {
      showError(err);
    }
  });
}

/* ----------------------------------------------------------- log actions -- */

function personnelOfUser() {
  return CONFIG.personnel;
}

/* Nothing is written until Save; Cancel leaves no empty entry behind.  Only
 * unambiguous choices are prefilled: the user's own person, and a vehicle or
 * pose source when exactly one exists. */
async function createLevel(level) {
  await catalogues; // a tap right after loading waits for the choices
  const c = state.catalogue;
  const values = {};
  if (level === "shift") {
    if (!c.vehicles.length) throw new ApiError("Configure a vehicle first (Configuration → Vehicles).");
    const me = byId(c.personnel, personnelOfUser());
    if (c.vehicles.length === 1) values.vehicle = c.vehicles[0].id;
    if (c.performers.length === 1) values.performer = c.performers[0].id;
    else if (me) values.performer = (c.performers.find((p) => p.institution === me.institution) || {}).id;
    if (me) Object.assign(values, { test_administrator: me.id, test_director: me.id, robot_operator: me.id, safety_officer: me.id });
  } else if (level === "leg" && c.poseSources.length === 1) {
    values.default_pose_source = c.poseSources[0].id;
  }
  const parent = LEVELS[level].parent;
  formDialog({
    title: `New ${LEVELS[level].label}`,
    subtitle: "Created when you press Save.",
    specs: fieldSpecs(level),
    values,
    save: async (body) => {
      if (parent) body[LEVELS[level].parentField] = state.selected[parent];
      const row = await api("POST", LEVELS[level].path, body);
      state.selected[level] = row.id;
      const child = LEVELS[level].child;
      if (child) state.selected[child] = null;
      await loadLevel(level);
      notice(`${LEVELS[level].label.charAt(0).toUpperCase()}${LEVELS[level].label.slice(1)} created.`);
    },
  });
}

function fieldSpecs(level) {
  const c = state.catalogue;
  const people = c.personnel.map((p) => [p.id, p.institution ? `${p.name} (${p.institution})` : p.name]);
  if (level === "event") {
    return [
      { name: "location", label: "Location" },
      { name: "version", label: "Version" },
      { name: "time_zone", label: "Time zone", list: "tz-list" },
      { name: "note", label: "Note", type: "textarea" },
    ];
  }
  if (level === "shift") {
    return [
      { name: "performer", label: "Performer", options: c.performers.map((p) => [p.id, p.institution]) },
      { name: "test_director", label: "Test director", options: people },
      { name: "test_administrator", label: "Test administrator", options: people },
      { name: "robot_operator", label: "Robot operator", options: people },
      { name: "safety_officer", label: "Safety officer", options: people },
      { name: "test_intent", label: "Test intent" },
      { name: "workspace", label: "Workspace" },
      { name: "vehicle", label: "Vehicle", options: c.vehicles.map((v) => [v.id, v.short_description]), required: true },
      { name: "note", label: "Note", type: "textarea" },
    ];
  }
  return [
    { name: "weather", label: "Weather", options: c.weather.map((w) => [w.key, w.short_description]) },
    { name: "default_pose_source", label: "Pose source", options: c.poseSources.map((p) => [p.id, p.short_description]) },
    { name: "note", label: "Note", type: "textarea" },
  ];
}

function ensureTimeZoneList() {
  if ($("#tz-list")) return;
  const list = document.createElement("datalist");
  list.id = "tz-list";
  const zones = Intl.supportedValuesOf ? Intl.supportedValuesOf("timeZone") : ["UTC"];
  list.append(...["UTC", ...zones].map((z) => new Option(z)));
  document.body.append(list);
}

function buildField(spec, value) {
  const label = document.createElement("label");
  label.textContent = spec.label;
  let input;
  if (spec.options) {
    input = document.createElement("select");
    if (!spec.required) input.append(new Option("—", ""));
    input.append(...spec.options.map(([v, text]) => new Option(text, v)));
    input.value = value === null || value === undefined ? "" : String(value);
  } else if (spec.type === "textarea") {
    input = document.createElement("textarea");
    input.rows = 3;
    input.value = value || "";
  } else {
    input = document.createElement("input");
    input.value = value ?? "";
    if (spec.number) input.inputMode = "decimal";
    if (spec.list) {
      ensureTimeZoneList();
      input.setAttribute("list", spec.list);
    }
  }
  input.name = spec.name;
  label.append(input);
  return label;
}

function readField(spec, form) {
  const raw = form.elements[spec.name].value;
  if (!spec.options) return raw;
  if (raw === "") return null;
  return /^\d+$/.test(raw) && typeof spec.options[0][0] === "number" ? Number(raw) : raw;
}

/* A dialog whose Save runs `save`; it stays open and shows the server's words
 * when the save is refused. */
function formDialog({ title, subtitle, specs, values, save }) {
  const dialog = $("#form-dialog");
  const form = $("form", dialog);
  $(".title", dialog).textContent = title;
  $(".subtitle", dialog).textContent = subtitle || "";
  const errorBox = $(".dialog-error", dialog);
  clearError(errorBox);
  $(".fields", dialog).replaceChildren(...specs.map((s) => buildField(s, values[s.name])));
  const readOnly = !CONFIG.canOperate;
  $$(".fields input, .fields select, .fields textarea", dialog).forEach((el) => (el.disabled = readOnly));
  $('button[value="save"]', dialog).hidden = readOnly;
  form.onsubmit = async (e) => {
    e.preventDefault();
    const body = Object.fromEntries(specs.map((s) => [s.name, readField(s, form)]));
    clearError(errorBox);
    try {
      await save(body);
      dialog.close();
    } catch (err) {
      showError(err, errorBox);
    }
  };
  $(".close", dialog).onclick = () => dialog.close();
  dialog.showModal();
}

async function editLevel(level) {
  await catalogues;
  const row = current(level);
  if (!row) return;
  const name = level === "event" ? `Test event #${row.id}` : level === "shift" ? `Shift ${row.number}` : `Leg ${row.number}`;
  formDialog({
    title: name,
    subtitle: `Started ${fmtTime(row.start)}${row.end ? `, ended ${fmtTime(row.end)}` : ""}`,
    specs: fieldSpecs(level),
    values: row,
    save: async (body) => {
      await api("PATCH", `${LEVELS[level].path}${row.id}/`, body);
      await loadLevel(level);
      notice("Saved.");
    },
  });
}

function confirmDialog(message, { yes = "Delete", no = "Keep it", warn = true } = {}) {
  const dialog = $("#confirm-dialog");
  $(".message", dialog).textContent = message;
  $(".undo-warning", dialog).hidden = !warn;
  $('button[value="yes"]', dialog).textContent = yes;
  $('button[value="no"]', dialog).textContent = no;
  dialog.returnValue = "";
  dialog.showModal();
  return new Promise((resolve) => dialog.addEventListener("close", () => resolve(dialog.returnValue === "yes"), { once: true }));
}

function describe(level, row) {
  if (level === "event") return `test event #${row.id} (${row.location || "no location"}) with all its shifts, legs, segments, notes and images`;
  if (level === "shift") return `shift ${row.number} with all its legs, segments, notes, images and maps`;
  return `leg ${row.number} with all its segments, notes and images`;
}

async function levelAction(level, action) {
  const row = current(level);
  if (action === "new") return createLevel(level);
  if (action === "edit") return editLevel(level);
  if (!row) return;
  if (action === "delete") {
    if (!(await confirmDialog(`Delete ${describe(level, row)}?`))) return;
    await api("DELETE", `${LEVELS[level].path}${row.id}/`);
    state.selected[level] = null;
    await loadLevel(level, true);
    return notice(`Deleted ${describe(level, row).split(" with ")[0]}.`);
  }
  // The server stops logging into what ends (one rule, in its services).
  if (action === "end") await api("POST", `${LEVELS[level].path}${row.id}/close/`, {});
  if (action === "reopen") await api("POST", `${LEVELS[level].path}${row.id}/reopen/`, {});
  await loadLevel(level);
  return notice(action === "end" ? `Ended ${describe(level, row).split(" with ")[0]}.` : "Re-opened.");
}

$$(".log-row [data-action]").forEach((b) =>
  b.addEventListener("click", async () => {
    clearError();
    try {
      await levelAction(b.dataset.level, b.dataset.action);
    } catch (err) {
      showError(err);
    }
  }),
);

/* -------------------------------------------------------------- segments -- */

const gpsMap = new FttMaps.GpsMap($("#gps-map"), $("#tile-message"));
const localMap = new FttMaps.LocalMap($("#local-map"));
for (const m of [gpsMap, localMap]) m.labelOf = (id) => segmentLabel(id);

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

/* The leg's AUTO/ITO bars over time; ITO bars take their reason's colour. */
const Timeline = {
  render() {
    const strip = $("#timeline");
    if (!strip) return;
    const masters = state.segments.filter((s) => s.parent === null).sort((a, b) => (a.start < b.start ? -1 : 1));
    strip.hidden = masters.length === 0;
    if (!masters.length) return strip.replaceChildren();
    const now = Date.now();
    const t0 = new Date(masters[0].start).getTime();
    const t1 = Math.max(...masters.map((m) => (m.end ? new Date(m.end).getTime() : now)), t0 + 1000);
    strip.replaceChildren(...masters.map((m) => {
      const start = new Date(m.start).getTime();
      const end = m.end ? new Date(m.end).getTime() : now;
      const child = state.segments.find((c) => c.parent === m.id);
      const target = child || m;
      const b = document.createElement("button");
      b.type = "button";
      b.className = `bar ${m.segment_type}${[m.id, target.id].includes(state.segment) ? " selected" : ""}`;
      b.style.left = `${((start - t0) / (t1 - t0)) * 100}%`;
      b.style.width = `${Math.max(((end - start) / (t1 - t0)) * 100, 0.6)}%`;
      const reason = child && (state.catalogue.reasons || []).find((r) => r.key === child.ito_reason);
      if (reason && reason.color) b.style.background = `rgb(${reason.color})`;
      const what = child ? `ITO, ${reasonName(child.ito_reason)}` : m.segment_type.toUpperCase();
      b.setAttribute("aria-label", `${segmentLabel(target.id)}: ${what}, ${fmtDuration(m.start, m.end)}`);
      b.title = b.getAttribute("aria-label");
      b.addEventListener("click", () => selectSegment(target.id));
      return b;
    }));
  },
};

function tileUrl() {
  const own = localStorage.getItem("ftt.tileUrl");
  return own !== null ? own : CONFIG.tileUrl;
}
gpsMap.setTiles(tileUrl(), CONFIG.tileAttribution);

async function loadBasemaps() {
  const event = state.selected.event;
  if (state.basemapsOf === event) return;
  state.basemapsOf = event;
  const query = event ? `?event=${event}` : "";
  const data = await api("GET", `basemaps/${query}`, undefined, { root: CONFIG.guiApiRoot });
  gpsMap.setBasemaps(data.layers);
}

async function selectionChanged() {
  const leg = current("leg");
  const restoring = state.shownLeg === undefined && fromUrl.leg === state.selected.leg ? fromUrl.segment : null;
  state.shownLeg = state.selected.leg;
  $("#segments-section").hidden = !leg;
  $("#maps-section").hidden = !leg;
  $("#mode-panel").hidden = !leg;
  Live.subscribe();
  Collector.refresh();
  state.segment = null;
  state.segments = [];
  state.tracks = {};
  state.labels = {};
  gpsMap.clear();
  localMap.clear();
  if (!leg) {
    renderSegments();
    return;
  }
  await Promise.all([loadBasemaps(), loadSegments(), loadTracks(), loadLocalMap()]);
  gpsMap.invalidate();
  gpsMap.fitAll();
  localMap.invalidate();
  localMap.fitAll();
  if (restoring && byId(state.segments, restoring)) selectSegment(restoring);
  else saveUrl();
}

async function loadSegments() {
  const leg = state.selected.leg;
  const [rows, named] = await Promise.all([
    list("segments/", { leg }),
    api("GET", `legs/${leg}/labels/`, undefined, { root: CONFIG.guiApiRoot }),
  ]);
  if (leg !== state.selected.leg) return;
  state.segments = rows;
  state.labels = named.labels;
  renderSegments();
}

async function loadTracks() {
  const leg = state.selected.leg;
  const data = await api("GET", `legs/${leg}/tracks/`, undefined, { root: CONFIG.guiApiRoot });
  if (leg !== state.selected.leg) return;
  state.tracks = data.segments;
  for (const [id, t] of Object.entries(data.segments)) {
    const sid = Number(id);
    if (t.gps.length) gpsMap.setTrack(sid, t.mode, t.gps);
    if (t.local.length) localMap.setTrack(sid, t.mode, t.local);
  }
  drawTakeOvers();
  const anyLocal = Object.values(data.segments).some((t) => t.local.length);
  if (anyLocal && !$("#show-local").checked) {
    $("#show-local").checked = true;
    showMaps();
  }
  renderSegments();
}

function drawTakeOvers() {
  gpsMap.markers.clearLayers();
  localMap.markers.clearLayers();
  for (const s of state.segments) {
    if (s.parent !== null || s.segment_type !== "ito") continue;
    const t = state.tracks[s.id];
    const gps = s.start_position ? [s.start_position.coordinates[1], s.start_position.coordinates[0]] : t && t.gps[0];
    if (gps) gpsMap.addTakeOver(s.id, gps);
    const local = s.start_local_x !== null && s.start_local_x !== undefined ? [s.start_local_x, s.start_local_y] : t && t.local[0];
    if (local) localMap.addTakeOver(s.id, local);
  }
}

function visibleSegments() {
  const itoOnly = $("#ito-only").checked;
  // AUTO masters and ITO reasons (children); an ITO master is shown through its children.
  return state.segments
    .filter((s) => (s.parent === null ? s.segment_type === "auto" && !itoOnly : true))
    .sort((a, b) => (a.start < b.start ? 1 : a.start > b.start ? -1 : b.id - a.id));
}

function renderSegments() {
  renderMode();
  updateSegmentButtons();
  Timeline.render();
  const tbody = $("#segment-table tbody");
  const rows = visibleSegments();
  $("#segments-empty").hidden = rows.length > 0 || !state.selected.leg;
  tbody.replaceChildren(...rows.map((s) => {
    const tr = document.createElement("tr");
    tr.dataset.id = s.id;
    tr.className = `${s.segment_type} ${s.parent === null ? "master" : "child"}${s.id === state.segment ? " selected" : ""}`;
    const master = s.parent === null ? s.id : s.parent;
    const track = state.tracks[master];
    const cells = [
      { text: shortLabel(s.id), title: `${segmentLabel(s.id)} (database id ${s.id})` },
      s.segment_type.toUpperCase(),
      s.parent === null ? "" : reasonName(s.ito_reason),
      { text: fmtClock(s.start), title: fmtTime(s.start) },
      s.end ? { text: fmtClock(s.end), title: fmtTime(s.end) } : "—",
      fmtDuration(s.start, s.end),
      fmtDistance(track ? track.distance_m : null),
      s.is_open ? "OPEN" : "CLOSED",
    ];
    tr.replaceChildren(...cells.map((c) => {
      const td = document.createElement("td");
      td.textContent = typeof c === "object" ? c.text : c;
      if (typeof c === "object") td.title = c.title;
      return td;
    }));
    tr.addEventListener("click", () => selectSegment(s.id === state.segment ? null : s.id));
    tr.addEventListener("dblclick", () => {
      selectSegment(s.id);
      openSegmentDialog(s.id);
    });
    return tr;
  }));
}

function selectSegment(id) {
  state.segment = id;
  saveUrl();
  updateSegmentButtons();
  Timeline.render();
  $$("#segment-table tbody tr").forEach((tr) => tr.classList.toggle("selected", Number(tr.dataset.id) === id));
  const s = byId(state.segments, id);
  const master = s ? (s.parent === null ? s.id : s.parent) : null;
  gpsMap.select(master);
  localMap.select(master);
}

$("#ito-only").addEventListener("change", renderSegments);

async function segmentAction(fn) {
  clearError();
  try {
    await fn();
  } catch (err) {
    showError(err);
  }
}

/* The mode now: the open master segment of the leg, big, with its duration. */
function openMaster() {
  return state.segments.find((s) => s.parent === null && s.is_open) || null;
}

function renderMode() {
  const panel = $("#mode-panel");
  const m = openMaster();
  const mode = m ? m.segment_type : "none";
  panel.dataset.mode = mode;
  $("#mode-name").textContent = m ? mode.toUpperCase() : "No open segment";
  $("#mode-since").textContent = m ? `for ${fmtDuration(m.start, null)} · ${segmentLabel(m.id)}` : "";
}

/* Reasons belong to take-overs: the buttons only work with an ITO row selected. */
function updateSegmentButtons() {
  const s = byId(state.segments, state.segment);
  const ito = Boolean(s && s.parent !== null);
  const why = s ? (ito ? "" : "Reasons can only be given to ITO rows.") : "Select an ITO row first.";
  for (const b of $$("[data-quick], #reason-apply")) {
    b.disabled = !CONFIG.canOperate || !ito;
    b.title = why;
  }
  $("#segment-end").disabled = !CONFIG.canOperate || !(s && s.is_open);
  $("#segment-edit").disabled = !s;
}

function requireSegment() {
  if (!state.segment) throw new ApiError("Select a segment in the list first.");
  return state.segment;
}

async function setReason(key) {
  const id = requireSegment();
  await api("PATCH", `segments/${id}/`, { ito_reason: key });
  await loadSegments();
  notice(`Reason of ${segmentLabel(id)} set to ${reasonName(key)}.`);
}

$$("[data-quick]").forEach((b) => b.addEventListener("click", () => segmentAction(() => setReason(b.dataset.quick))));
$("#reason-apply").addEventListener("click", () => segmentAction(() => setReason($("#reason-any").value)));
$("#segment-new").addEventListener("click", () => segmentAction(async () => {
  const m = openMaster();
  if (m && m.segment_type === "auto") {
    const ok = await confirmDialog("The robot is in AUTO. Record a take-over (ITO) now?", { yes: "Record take-over", no: "Cancel", warn: false });
    if (!ok) return;
  }
  const child = await api("POST", `legs/${state.selected.leg}/manual-segment/`, {});
  await loadSegments();
  if (child && child.id) selectSegment(child.id);
  notice("Take-over recorded.");
}));
$("#segment-end").addEventListener("click", () => segmentAction(async () => {
  const id = requireSegment();
  await api("POST", `segments/${id}/close/`, {});
  await loadSegments();
  notice(`Ended ${segmentLabel(id)}.`);
}));
$("#segment-edit").addEventListener("click", () => segmentAction(async () => openSegmentDialog(requireSegment())));

/* -------------------------------------------------------- segment dialog -- */

const segmentDialog = $("#segment-dialog");
let dialogSegment = null;

async function openSegmentDialog(id) {
  const s = await api("GET", `segments/${id}/`);
  dialogSegment = s;
  const errorBox = $(".dialog-error", segmentDialog);
  errorBox.hidden = true;
  const kind = s.segment_type === "ito" ? (s.parent === null ? "ITO (take-over)" : "ITO reason") : "AUTO";
  $(".title", segmentDialog).textContent = `${segmentLabel(s.id)} · ${kind}`;
  $(".subtitle", segmentDialog).textContent = `Start ${fmtTime(s.start)} · End ${s.end ? fmtTime(s.end) : "still open"}`;
  const form = $("#annotation-form");
  form.elements.ito_reason.replaceChildren(...state.catalogue.reasons.map((r) => new Option(r.short_description, r.key)));
  form.elements.ito_reason.value = s.ito_reason || "unassigned";
  for (const f of ["obstacle", "lighting", "slope"]) form.elements[f].value = s[f] || "";
  // Annotation belongs to take-over reasons; the server says so too if tried elsewhere.
  form.hidden = s.parent === null;
  $$("input, select, button", form).forEach((el) => (el.disabled = !CONFIG.canOperate));
  $$(".op-block", segmentDialog).forEach((el) => (el.hidden = !CONFIG.canOperate));
  await Promise.all([loadNotes(), loadImages()]);
  if (!segmentDialog.open) segmentDialog.showModal();
}

$(".close", segmentDialog).addEventListener("click", () => segmentDialog.close());
segmentDialog.addEventListener("close", () => {
  dialogSegment = null;
  loadSegments().catch(showError);
});

function dialogAction(fn) {
  return async (e) => {
    if (e) e.preventDefault();
    const errorBox = $(".dialog-error", segmentDialog);
    errorBox.hidden = true;
    try {
      await fn(e);
    } catch (err) {
      showError(err, errorBox);
    }
  };
}

$("#annotation-form").addEventListener("submit", dialogAction(async () => {
  const form = $("#annotation-form");
  const body = {};
  for (const f of ["ito_reason", "obstacle", "lighting", "slope"]) body[f] = form.elements[f].value;
  await api("PATCH", `segments/${dialogSegment.id}/`, body);
  notice(`${segmentLabel(dialogSegment.id)} saved.`);
}));

async function loadNotes({ keepEditing = false } = {}) {
  if (!dialogSegment) return;
  const notes = await list("notes/", { segment: dialogSegment.id });
  const ul = $(".notes", segmentDialog);
  // Checked after the fetch: the operator may have started editing meanwhile.
  if (keepEditing && $("textarea", ul)) return;
  if (!notes.length) {
    const li = document.createElement("li");
    li.className = "muted";
    li.textContent = "No notes yet.";
    ul.replaceChildren(li);
    return;
  }
  ul.replaceChildren(...notes.map((n) => {
    const li = document.createElement("li");
    li.dataset.id = n.id;
    const meta = document.createElement("div");
    meta.className = "meta";
    const edited = n.edited && n.edited !== n.created ? ` · edited ${fmtTime(n.edited)}` : "";
    meta.textContent = `${n.author_name || "unknown author"} · ${fmtTime(n.created)}${edited}`;
    const text = document.createElement("div");
    text.className = "text";
    text.textContent = n.text;
    li.append(meta, text);
    if (CONFIG.canOperate) {
      const edit = document.createElement("button");
      edit.type = "button";
      edit.textContent = "Edit";
      edit.addEventListener("click", () => editNote(li, n));
      const del = document.createElement("button");
      del.type = "button";
      del.textContent = "Delete";
      del.className = "danger";
      del.addEventListener("click", dialogAction(async () => {
        if (!(await confirmDialog(`Delete this note by ${n.author_name || "unknown author"}?`))) return;
        await api("DELETE", `notes/${n.id}/`);
        await loadNotes();
      }));
      const buttons = document.createElement("div");
      buttons.className = "buttons";
      buttons.append(edit, del);
      li.append(buttons);
    }
    return li;
  }));
}

function editNote(li, note) {
  const area = document.createElement("textarea");
  area.value = note.text;
  area.rows = 3;
  area.setAttribute("aria-label", "Note text");
  const save = document.createElement("button");
  save.type = "button";
  save.className = "primary";
  save.textContent = "Save note";
  save.addEventListener("click", dialogAction(async () => {
    await api("PATCH", `notes/${note.id}/`, { text: area.value });
    await loadNotes();
  }));
  const cancel = document.createElement("button");
  cancel.type = "button";
  cancel.textContent = "Cancel";
  cancel.addEventListener("click", () => loadNotes());
  const buttons = document.createElement("div");
  buttons.className = "buttons";
  buttons.append(save, cancel);
  $(".text", li).replaceWith(area);
  $(".buttons", li).replaceWith(buttons);
  area.focus();
}

$("#note-form").addEventListener("submit", dialogAction(async () => {
  const form = $("#note-form");
  const body = { segment: dialogSegment.id, text: form.elements.text.value };
  if (CONFIG.personnel) body.author = CONFIG.personnel;
  await api("POST", "notes/", body);
  form.reset();
  await loadNotes();
}));

function masterOf(s) {
  return s.parent === null ? s.id : s.parent;
}

async function loadImages() {
  if (!dialogSegment) return;
  const images = await list("images/", { segment: masterOf(dialogSegment) });
  const box = $(".images", segmentDialog);
  if (!images.length) {
    const p = document.createElement("p");
    p.className = "muted";
    p.textContent = "No images yet.";
    box.replaceChildren(p);
    return;
  }
  box.replaceChildren(...images.map((im) => {
    const fig = document.createElement("figure");
    const img = document.createElement("img");
    img.src = im.url || im.image;
    img.alt = im.description || `Image ${im.id}`;
    img.loading = "lazy";
    img.addEventListener("click", () => {
      const d = $("#image-dialog");
      $("img", d).src = img.src;
      $(".caption", d).textContent = `${im.description || ""} ${fmtTime(im.robot_stamp || im.received)}`;
      d.showModal();
    });
    const cap = document.createElement("figcaption");
    cap.textContent = im.description || fmtTime(im.received);
    fig.append(img, cap);
    if (CONFIG.canOperate) {
      const del = document.createElement("button");
      del.type = "button";
      del.className = "danger";
      del.textContent = "Delete";
      del.addEventListener("click", dialogAction(async () => {
        if (!(await confirmDialog("Delete this image?"))) return;
        await api("DELETE", `images/${im.id}/`);
        await loadImages();
      }));
      fig.append(del);
    }
    return fig;
  }));
}

$$(".upload input[type=file]", segmentDialog).forEach((input) =>
  input.addEventListener("change", dialogAction(async () => {
    const file = input.files[0];
    if (!file) return;
    const body = new FormData();
    body.append("segment", masterOf(dialogSegment));
    body.append("image", file, file.name);
    body.append("description", `Uploaded by ${CONFIG.user}`);
    await api("POST", "images/", body);
    input.value = "";
    await loadImages();
    notice("Image uploaded.");
  })),
);

/* ------------------------------------------------------------------ maps -- */

function showMaps() {
  $("#gps-map").hidden = !$("#show-gps").checked;
  $("#local-map").hidden = !$("#show-local").checked;
  $("#local-message").hidden = !$("#show-local").checked || !$("#local-message").textContent;
  gpsMap.invalidate();
  localMap.invalidate();
}
$("#show-gps").addEventListener("change", showMaps);
$("#show-local").addEventListener("change", showMaps);

async function loadLocalMap() {
  const shift = state.selected.shift;
  if (!shift) return;
  const data = await api("GET", `shifts/${shift}/local-map/`, undefined, { root: CONFIG.guiApiRoot });
  if (shift !== state.selected.shift) return;
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

/* ------------------------------------------------------------------ live -- */

const Live = {
  socket: null,
  retry: 500,
  pending: new Set(),
  timer: null,
  connect() {
    const scheme = location.protocol === "https:" ? "wss:" : "ws:";
    const socket = new WebSocket(`${scheme}//${location.host}${CONFIG.wsPath}`);
    this.socket = socket;
    socket.onopen = () => {
      this.retry = 500;
      this.setStatus("live", "ok");
      this.subscribe();
    };
    socket.onmessage = (e) => this.receive(JSON.parse(e.data));
    socket.onclose = (e) => {
      if (this.socket !== socket) return;
      if (e.code === 4403) {
        this.setStatus("no live updates (no role)", "bad");
        return;
      }
      this.setStatus("reconnecting…", "bad");
      setTimeout(() => this.connect(), this.retry);
      this.retry = Math.min(this.retry * 2, 5000);
    };
  },
  setStatus(text, kind) {
    const badge = $("#live-status");
    badge.textContent = text;
    badge.className = `badge ${kind || ""}`;
    badge.dataset.state = kind || "";
  },
  subscribe() {
    if (!this.socket || this.socket.readyState !== WebSocket.OPEN) return;
    this.socket.send(JSON.stringify({
      type: "subscribe",
      test_event: state.selected.event,
      shift: state.selected.shift,
      leg: state.selected.leg,
      last_id: state.lastEventId,
    }));
  },
  receive(message) {
    if (message.type === "subscribed") {
      if (state.lastEventId === null || message.last_id > state.lastEventId) state.lastEventId = message.last_id;
      return;
    }
    if (message.type === "reset") {
      state.lastEventId = message.last_id;
      state.shownLeg = undefined;
      this.later("logs");
      return;
    }
    if (message.type !== "events") return;
    for (const e of message.events) {
      if (e.id > (state.lastEventId || 0)) state.lastEventId = e.id;
      this.apply(e);
    }
  },
  apply(e) {
    const mine = e.leg !== null && e.leg === state.selected.leg;
    switch (e.kind) {
      case "log":
        this.later("logs");
        // Closing a level closes the segments below it.
        if (e.test_event === state.selected.event) this.later("segments");
        break;
      case "deleted": {
        const what = { note: "notes", image: "images", segment: "segments", mapimage: "map" }[e.payload.model];
        this.later(what || "logs");
        break;
      }
      case "segment":
        if (mine) this.later("segments");
        break;
      case "note":
        this.later("notes");
        break;
      case "image":
        this.later("images");
        break;
      case "poses":
      case "local_poses": {
        if (!mine) break;
        const p = e.payload;
        if (!p.points) {
          this.later("tracks");
          break;
        }
        const map = e.kind === "poses" ? gpsMap : localMap;
        const pts = e.kind === "poses" ? p.points.map(([lon, lat]) => [lat, lon]) : p.points;
        map.appendPoints(p.segment, p.mode, pts);
        const t = state.tracks[p.segment] || (state.tracks[p.segment] = { mode: p.mode, gps: [], local: [], distance_m: null });
        (e.kind === "poses" ? t.gps : t.local).push(...pts);
        this.later("distances");
        break;
      }
      case "map":
        if (e.shift === state.selected.shift) this.later("map");
        break;
      case "command": {
        const c = Collector.status && Collector.status.collector;
        if (c && e.collector === c.id) {
          if (e.payload.success === false) showError(new ApiError(`The robot refused: ${e.payload.message}`));
          else if (e.payload.message) notice(`Robot: ${e.payload.message}`);
        }
        Collector.refresh();
        break;
      }
      case "collector":
        Collector.refresh();
        break;
      default:
        break;
    }
  },
  /* Bursts of events become one refresh per kind. */
  later(what) {
    this.pending.add(what);
    if (this.timer) return;
    this.timer = setTimeout(() => this.flush(), 40);
  },
  async flush() {
    const what = this.pending;
    this.pending = new Set();
    this.timer = null;
    try {
      if (what.has("logs")) await loadLevel("event");
      if (state.selected.leg) {
        if (what.has("segments")) {
          await loadSegments();
          drawTakeOvers();
        }
        if (what.has("tracks") || what.has("distances")) await refreshDistances(what.has("tracks"));
        if (what.has("map")) await loadLocalMap();
      }
      // A note being edited is not thrown away by somebody else's change.
      if (dialogSegment && what.has("notes")) await loadNotes({ keepEditing: true });
      if (dialogSegment && what.has("images")) await loadImages();
    } catch (err) {
      showError(err);
    }
  },
};

/* Distances come from the server (geodesic); redrawing is only needed when a
 * batch was too large to be sent inline. */
async function refreshDistances(redraw) {
  const leg = state.selected.leg;
  if (!leg) return;
  if (refreshDistances.busy) return;
  refreshDistances.busy = true;
  try {
    const data = await api("GET", `legs/${leg}/tracks/`, undefined, { root: CONFIG.guiApiRoot });
    if (leg !== state.selected.leg) return;
    for (const [id, t] of Object.entries(data.segments)) {
      const sid = Number(id);
      if (redraw || !state.tracks[id]) {
        if (t.gps.length) gpsMap.setTrack(sid, t.mode, t.gps);
        if (t.local.length) localMap.setTrack(sid, t.mode, t.local);
      }
    }
    state.tracks = data.segments;
    renderSegments();
  } finally {
    refreshDistances.busy = false;
  }
}

/* ------------------------------------------------------------- collector -- */

const Collector = {
  status: null,
  async refresh() {
    const box = $("#collector-status");
    const button = $("#logging-toggle");
    const shift = current("shift");
    $("#collector").hidden = !shift;
    if (!shift) {
      this.vehicle = null;
      box.textContent = "Select a shift to see its robot.";
      button.disabled = true;
      return;
    }
    if (this.vehicle !== shift.vehicle) {
      this.vehicle = shift.vehicle;
      box.textContent = "Asking for the robot's status…";
    }
    try {
      this.status = await api("GET", `collectors/?vehicle=${shift.vehicle}&leg=${state.selected.leg || ""}`, undefined, { root: CONFIG.guiApiRoot });
    } catch (err) {
      this.status = null;
      box.textContent = err.status === 404 ? "Collector status is not available on this server." : plainMessage(err);
      button.disabled = true;
      return;
    }
    this.render();
  },
  render() {
    const s = this.status;
    const button = $("#logging-toggle");
    const inputs = $("#collector-inputs");
    if (!s || !s.collector) {
      $("#collector-status").textContent = `No collector has reported for ${vehicleName(current("shift").vehicle)}.`;
      inputs.replaceChildren();
      button.disabled = true;
      button.textContent = "Start logging";
      $("#logging-why").textContent = "";
      return;
    }
    const c = s.collector;
    const into = c.leg === state.selected.leg ? "this leg" : c.leg ? "another leg" : "no leg";
    const doing = c.logging ? `logging into ${into}` : "not logging";
    const queue = c.pending ? ` · ${c.pending} records not yet stored` : "";
    // Set by the collector's watchdog, e.g. "robot publishes, collector hears nothing (…)".
    const hearing = c.online && c.hearing ? ` · ${c.hearing}` : "";
    $("#collector-status").textContent = `${vehicleName(current("shift").vehicle)} (collector ${c.name}): ${c.online ? "online" : "offline"}, ${doing}${queue}${hearing}`;
    inputs.replaceChildren(...Object.entries(c.inputs || {}).map(([name, info]) => {
      const li = document.createElement("li");
      const age = info && typeof info.age === "number" ? `${info.age.toFixed(1)} s ago` : "no data yet";
      li.textContent = `${name}: ${age}`;
      return li;
    }));
    button.textContent = c.logging ? "Stop logging" : "Start logging";
    button.disabled = !CONFIG.canOperate || !s.can_toggle;
    $("#logging-why").textContent = s.reason || "";
    $("#open-parameters").hidden = !CONFIG.canOperate || !c.online;
  },
  async command(kind, args = {}) {
    const c = this.status && this.status.collector;
    if (!c) throw new ApiError("No collector is connected for this vehicle.");
    const result = await api("POST", `collectors/${c.id}/commands/`, { kind, arguments: args, leg: state.selected.leg }, { root: CONFIG.guiApiRoot });
    await this.refresh();
    return result;
  },
};

$("#logging-toggle").addEventListener("click", async () => {
  clearError();
  try {
    const c = Collector.status && Collector.status.collector;
    await Collector.command(c && c.logging ? "stop_logging" : "start_logging");
  } catch (err) {
    showError(err);
  }
});

/* ------------------------------------------------------- ROS parameters -- */

$("#open-parameters").addEventListener("click", () => Parameters.open());

/* Rendered from the collector's parameter schema (type, bounds, choices,
 * message types); the server checks every value against the same schema. */
/* ROS floats are 32-bit: 0.10000000149011612 is shown as 0.1. */
const roundFloat = (v) => (typeof v === "number" ? Number(v.toPrecision(7)) : v);

const Parameters = {
  input(row) {
    let input;
    if (row.type === "bool") {
      input = document.createElement("select");
      input.append(new Option("true", "true"), new Option("false", "false"));
      input.value = String(row.value);
    } else if (row.choices) {
      input = document.createElement("select");
      input.append(...row.choices.map((c) => new Option(c, c)));
      input.value = row.value;
    } else {
      input = document.createElement("input");
      input.value = row.type === "float" ? roundFloat(row.value) : row.value;
      if (row.type === "int" || row.type === "float") {
        input.type = "number";
        input.step = row.type === "int" ? "1" : "any";
        if (row.minimum !== null) input.min = String(row.minimum);
        if (row.maximum !== null) input.max = String(row.maximum);
      }
      if (row.suggestions.length) {
        const list = document.createElement("datalist");
        list.id = `topics-${row.name.replace(/\W/g, "-")}`;
        list.append(...row.suggestions.map((t) => new Option(t)));
        input.setAttribute("list", list.id);
        input.after(list);
        input._list = list;
      }
    }
    input.name = row.name;
    input.setAttribute("aria-label", row.name);
    return input;
  },
  read(row, input) {
    if (row.type === "bool") return input.value === "true";
    if (row.type === "int") return Number.parseInt(input.value, 10);
    // An untouched float keeps its exact value, not the rounded one shown.
    if (row.type === "float") return input.value === String(roundFloat(row.value)) ? row.value : Number.parseFloat(input.value);
    return input.value;
  },
  open() {
    const d = $("#parameters-dialog");
    const body = $(".parameters-body", d);
    const errorBox = $(".dialog-error", d);
    errorBox.hidden = true;
    const rows = (Collector.status && Collector.status.parameters) || [];
    const table = document.createElement("table");
    table.className = "params";
    const inputs = new Map();
    for (const row of rows) {
      const tr = document.createElement("tr");
      const name = document.createElement("td");
      name.textContent = row.name;
      name.title = row.description;
      const cell = document.createElement("td");
      const input = this.input(row);
      cell.append(input);
      if (input._list) cell.append(input._list);
      const help = document.createElement("td");
      help.className = "muted";
      help.textContent = row.expects.length ? row.expects.join(", ") : row.description;
      tr.append(name, cell, help);
      table.append(tr);
      inputs.set(row.name, [row, input]);
    }
    const apply = document.createElement("button");
    apply.type = "button";
    apply.className = "primary";
    apply.textContent = "Apply";
    apply.addEventListener("click", async () => {
      errorBox.hidden = true;
      const changes = {};
      for (const [name, [row, input]] of inputs) {
        const value = this.read(row, input);
        if (value !== row.value) changes[name] = value;
      }
      if (!Object.keys(changes).length) return showError(new ApiError("Nothing was changed."), errorBox);
      try {
        await Collector.command("set_parameters", { parameters: changes });
        notice("Parameters sent to the robot.");
      } catch (err) {
        showError(err, errorBox);
      }
    });
    const save = document.createElement("button");
    save.type = "button";
    save.textContent = "Save to the node's YAML file";
    save.addEventListener("click", async () => {
      errorBox.hidden = true;
      try {
        await Collector.command("save_parameters");
        notice("Asked the robot to save its parameters.");
      } catch (err) {
        showError(err, errorBox);
      }
    });
    const buttons = document.createElement("div");
    buttons.className = "buttons";
    buttons.append(apply, save);
    const empty = document.createElement("p");
    empty.textContent = "The collector has not reported its parameters yet.";
    body.replaceChildren(rows.length ? table : empty, buttons);
    $(".close", d).onclick = () => d.close();
    d.showModal();
  },
};

/* --------------------------------------------------------------- reports -- */

$("#open-reports").addEventListener("click", () => Reports.open().catch(showError));

const REPORT_FIELDS = [
  { name: "name", label: "Report name" },
  { name: "version", label: "Report version" },
  { name: "recipient", label: "Recipient" },
  { name: "recipient_address", label: "Recipient address", type: "textarea" },
  { name: "creator", label: "Creator" },
  { name: "creator_address", label: "Creator address", type: "textarea" },
  { name: "local", label: "Positions", options: [["false", "GPS"], ["true", "Local (map frame)"]], required: true },
  { name: "min_timeline_hours", label: "Timeline at least (hours, optional)", number: true },
  { name: "max_zoom", label: "Closest map zoom (1–19, optional)", number: true },
];
const EXPORTS = [
  ["segments.csv", "Segments (CSV)"],
  ["tracks.geojson", "Tracks (GeoJSON)"],
  ["tracks.gpx", "Tracks (GPX)"],
];

/* The report itself is made by the server (reports app); this dialog asks for
 * one, shows its progress and links the finished PDF. */
const Reports = {
  timer: null,
  async open() {
    const d = $("#reports-dialog");
    const body = $(".reports-body", d);
    $(".dialog-error", d).hidden = true;
    body.replaceChildren();
    const event = current("event");
    $(".close", d).onclick = () => d.close();
    if (!event) {
      const p = document.createElement("p");
      p.textContent = "Select a test event first.";
      body.append(p);
    } else {
      body.append(this.downloads(event), this.form(event), Object.assign(document.createElement("div"), { id: "report-list" }));
      await this.refresh(event);
    }
    if (!d.open) d.showModal();
  },
  downloads(event) {
    const p = document.createElement("p");
    p.append(`Data of test event #${event.id}: `);
    const archive = [`test-events/${event.id}/archive/`, "Everything (FTT archive, ZIP)"];
    for (const [path, label] of [...EXPORTS.map(([f, l]) => [`reports/exports/${event.id}/${f}`, l]), archive]) {
      const a = document.createElement("a");
      a.href = CONFIG.apiRoot + path;
      a.textContent = label;
      a.setAttribute("download", "");
      p.append(a, " ");
    }
    return p;
  },
  form(event) {
    const form = document.createElement("form");
    form.id = "report-form";
    const saved = JSON.parse(localStorage.getItem("ftt.reportFields") || "{}");
    const defaults = { version: "1.0", local: "false" };
    for (const spec of REPORT_FIELDS) form.append(buildField(spec, saved[spec.name] ?? defaults[spec.name] ?? ""));
    const go = document.createElement("button");
    go.type = "submit";
    go.className = "primary";
    go.textContent = "Generate report";
    go.disabled = !CONFIG.canOperate;
    form.append(go);
    form.addEventListener("submit", async (e) => {
      e.preventDefault();
      const errorBox = $("#reports-dialog .dialog-error");
      errorBox.hidden = true;
      const values = Object.fromEntries(REPORT_FIELDS.map((s) => [s.name, form.elements[s.name].value]));
      localStorage.setItem("ftt.reportFields", JSON.stringify(values));
      const lines = (text) => text.split("\n").map((l) => l.trim()).filter(Boolean);
      const options = {
        ...values,
        local: values.local === "true",
        recipient_address: lines(values.recipient_address),
        creator_address: lines(values.creator_address),
      };
      // Empty number fields mean "the server's default"; whatever else was typed
      // goes to the server as a number or as text, and the server says what is wrong.
      for (const spec of REPORT_FIELDS.filter((s) => s.number)) {
        const raw = values[spec.name].trim();
        if (raw === "") delete options[spec.name];
        else options[spec.name] = Number.isFinite(Number(raw)) ? Number(raw) : raw;
      }
      try {
        await api("POST", "reports/", { test_event: event.id, options });
        await this.refresh(event);
      } catch (err) {
        showError(err, errorBox);
      }
    });
    return form;
  },
  async refresh(event) {
    clearTimeout(this.timer);
    const box = $("#report-list");
    if (!box || !$("#reports-dialog").open && box.childElementCount) return;
    const rows = await api("GET", `reports/?test_event=${event.id}`);
    const list = Array.isArray(rows) ? rows : rows.results;
    const ul = document.createElement("ul");
    for (const r of list) {
      const li = document.createElement("li");
      const when = fmtTime(r.created);
      if (r.download) {
        const a = document.createElement("a");
        a.href = r.download;
        a.textContent = `Report of ${when} (PDF)`;
        li.append(a, r.provisional ? " — provisional: the test event was still open" : "");
      } else {
        li.textContent = `Report of ${when}: ${r.status}${r.progress !== null && r.progress !== undefined ? ` ${Math.round(r.progress * 100)} %` : ""}${r.error ? ` — ${r.error}` : r.message ? ` — ${r.message}` : ""}`;
      }
      ul.append(li);
    }
    const h = document.createElement("h3");
    h.textContent = list.length ? "Reports of this test event" : "No reports of this test event yet.";
    box.replaceChildren(h, ul);
    if (list.some((r) => r.status === "queued" || r.status === "running")) {
      this.timer = setTimeout(() => this.refresh(event).catch(showError), 1000);
    }
  },
};

/* ------------------------------------------------------------------ boot -- */

let catalogues = null;

async function boot() {
  catalogues = loadCatalogues();
  if (!CONFIG.canOperate) $$(".op").forEach((b) => (b.disabled = true));
  Live.connect();
  // Nothing in the address: offer the leg a collector is logging into.
  if (!fromUrl.event && CONFIG.loggingLeg) Object.assign(state.selected, CONFIG.loggingLeg);
  setInterval(renderMode, 1000);
  try {
    await catalogues;
    await loadLevel("event");
  } catch (err) {
    showError(err);
  }
  setInterval(() => {
    // Open segments' durations keep growing between events.
    if (state.segments.some((s) => s.is_open)) renderSegments();
    if (current("shift")) Collector.refresh();
  }, 5000);
}

if ($("#pick-event")) boot();
window.FTT = { state, Live, Collector };
