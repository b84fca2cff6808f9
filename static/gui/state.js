/* The page's one state object: selection (also in the address), loaded rows,
 * segments, tracks and catalogues, with the look-ups that read it. */

import { CONFIG } from "./dom.js";
import { _ } from "./i18n.js";

/* Each level's words are whole sentences: German declines "Testveranstaltung", "Schicht", "Etappe" differently. */
export const LEVELS = {
  event: {
    path: "test-events/", parent: null, child: "shift",
    newTitle: () => _("New test event"), created: () => _("Test event created."),
    choose: () => _("— choose a test event —"), none: () => _("no test event yet"),
  },
  shift: {
    path: "shifts/", parent: "event", parentField: "test_event", child: "leg",
    newTitle: () => _("New shift"), created: () => _("Shift created."),
    choose: () => _("— choose a shift —"), none: () => _("no shift yet"),
  },
  leg: {
    path: "legs/", parent: "shift", parentField: "shift", child: null,
    newTitle: () => _("New leg"), created: () => _("Leg created."),
    choose: () => _("— choose a leg —"), none: () => _("no leg yet"),
  },
};

/* Event, shift, leg, segment and the view live in the address, so reload and shared links restore them. */
export const fromUrl = (() => {
  const q = new URLSearchParams(location.search);
  const n = (k) => (/^\d+$/.test(q.get(k) || "") ? Number(q.get(k)) : null);
  const view = q.get("view") === "fleet" ? "fleet" : null;
  return { event: n("event"), shift: n("shift"), leg: n("leg"), segment: n("segment"), view };
})();

/* push: a new history entry (switching between fleet and cockpit), so that the
   browser's Back returns to the view before instead of leaving the app. */
export function saveUrl({ push = false } = {}) {
  const q = new URLSearchParams();
  for (const k of ["event", "shift", "leg"]) if (state.selected[k]) q.set(k, state.selected[k]);
  if (state.segment) q.set("segment", state.segment);
  if (state.view) q.set("view", state.view);
  const next = q.toString() ? `?${q}` : location.pathname;
  if (push && next !== location.search) history.pushState(null, "", next || location.pathname);
  else if (next !== location.search) history.replaceState(null, "", next || location.pathname);
  // The cockpit shown, for the server to open again at a bare address (a year).
  const { event, shift, leg } = state.selected;
  if (event && shift && leg) document.cookie = `${CONFIG.cockpitCookie}=${event}.${shift}.${leg}; path=/; max-age=31536000; SameSite=Lax`;
}

export const state = {
  rows: { event: [], shift: [], leg: [] },
  selected: { event: fromUrl.event, shift: fromUrl.shift, leg: fromUrl.leg },
  segments: [],
  tracks: {},
  labels: {}, // segment id -> "Leg 2 · #7", from the server
  shortLabels: {}, // segment id -> "#7", from the server
  shownLeg: undefined, // leg whose segments and tracks are drawn
  basemapsOf: undefined, // test event whose basemaps the switcher offers
  localMapOf: undefined, // shift whose map image and overlay are shown
  segment: null, // selected segment id
  openTakeOver: null, // the take-over quick reasons annotate, as the server says
  view: fromUrl.view, // "fleet": every logging vehicle on one map; null: the cockpit
  catalogue: {},
  // The change feed's newest event when the page's first answers were read: the
  // subscription brings what came after.
  lastEventId: CONFIG.lastEventId ?? null,
};

export const byId = (rows, id) => rows.find((r) => r.id === id) || null;
export const current = (level) => byId(state.rows[level], state.selected[level]);
export const vehicleName = (id) => (byId(state.catalogue.vehicles || [], id) || {}).short_description || _("vehicle %(id)s", { id });
export const segmentLabel = (id) => state.labels[id] || `segment ${id}`;
export const shortLabel = (id) => state.shortLabels[id] || "…";
export const reasonName = (key) => {
  const r = (state.catalogue.reasons || []).find((x) => x.key === key);
  return r ? r.label : key || "";
};
/* AUTO and ITO as the field writes them; a segment logged before the robot said its mode in words. */
export const modeName = (type) => (type === "unknown" ? _("Unknown mode") : (type || "").toUpperCase());
/* A segment row as the server answered it replaces the listed one, or joins the list. */
export function putSegment(row) {
  const i = state.segments.findIndex((s) => s.id === row.id);
  if (i >= 0) state.segments[i] = row;
  else state.segments.push(row);
}
