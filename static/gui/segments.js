/* The selected leg: its segments (list, timeline strip, current mode), their
 * tracks on the maps, and the segment actions (reasons, New, End, Edit). */
import { CONFIG, $, $$ } from "./dom.js";
import { _ } from "./i18n.js";
import { ApiError, api } from "./api.js";
import { Outbox, newUid } from "./outbox.js";
import { take } from "./bootstrap.js";
import { clearError, notice, showError } from "./feedback.js";
import { byId, current, fromUrl, modeName, putSegment, reasonName, saveUrl, segmentLabel, shortLabel, state, vehicleName } from "./state.js";
import { fmtClock, fmtDistance, fmtDuration, fmtTime } from "./format.js";
import { confirmDialog } from "./dialogs.js";
import { clearMaps, drawLegTracks, showPosition, showTakeOvers, gpsMap, loadBasemaps, loadLegTracks, loadLocalMap, localMap, showLegTracks } from "./mapview.js";
import { Live, onSelectedLeg } from "./live.js";
import { Collector } from "./collector.js";
import { keepLeg, keptLeg } from "./lastknown.js";
import { openSegmentDialog } from "./segment-dialog.js";
import { VirtualRows } from "./virtual-rows.js";

/* The leg's AUTO/ITO bars over a time axis; ITO bars take their reason's colour and
 * stripes, and say what they are in words where they are wide enough.  Each bar is
 * at least 44 px wide to tap; its coloured part keeps its true length. */
const Timeline = {
  bars: new Map(), // master id -> {key, b, x, w}: the bars on the strip and what they say
  track: null,
  axis: null,
  span: null, // the seconds the strip stands for
  render() {
    const strip = $("#timeline");
    if (!strip) return;
    const masters = state.segments.filter((s) => s.parent === null).sort((a, b) => (a.start < b.start ? -1 : 1));
    strip.hidden = masters.length === 0;
    if (!masters.length) {
      this.bars.clear();
      return strip.replaceChildren();
    }
    if (!this.track) {
      this.track = document.createElement("div");
      this.track.className = "track";
      this.axis = document.createElement("div");
      this.axis.className = "axis";
      this.axis.append(...[0, 1, 2].map(() => document.createElement("span")));
    }
    if (strip.firstChild !== this.track) strip.replaceChildren(this.track, this.axis);
    const firstChild = new Map();
    for (const s of state.segments) if (s.parent !== null && !firstChild.has(s.parent)) firstChild.set(s.parent, s);
    const now = Date.now();
    const t0 = new Date(masters[0].start).getTime();
    let t1 = t0 + 1000;
    for (const m of masters) t1 = Math.max(t1, m.end ? new Date(m.end).getTime() : now);
    // Only bars whose words changed are built again; the others only move along the axis.
    const shown = new Map();
    const bars = masters.map((m) => {
      const start = new Date(m.start).getTime();
      const end = m.end ? new Date(m.end).getTime() : now;
      const child = firstChild.get(m.id);
      const target = child || m;
      // Whether a reason has no annotation yet is the server's word (Segment.unannotated).
      const unassigned = child && child.unannotated ? " unassigned" : "";
      const className = `bar ${m.segment_type}${unassigned}${[m.id, target.id].includes(state.segment) ? " selected" : ""}`;
      const reason = child && (state.catalogue.reasons || []).find((r) => r.key === child.ito_reason);
      const color = reason && reason.color ? `rgb(${reason.color})` : "";
      const text = child ? `ITO · ${reasonName(child.ito_reason)}` : modeName(m.segment_type);
      const label = `${segmentLabel(target.id)}: ${text}, ${fmtDuration(m.start, m.end)}`;
      const key = JSON.stringify([className, color, text, label, target.id]);
      let bar = this.bars.get(m.id);
      if (!bar || bar.key !== key) bar = { key, b: this.bar(target.id, className, color, text, label) };
      // Seconds from the leg's start: a growing leg changes the strip's --span, not every bar.
      const x = String((start - t0) / 1000);
      const w = String((end - start) / 1000);
      if (bar.x !== x) bar.b.style.setProperty("--from", (bar.x = x));
      if (bar.w !== w) bar.b.style.setProperty("--length", (bar.w = w));
      shown.set(m.id, bar);
      return bar.b;
    });
    this.bars = shown;
    // The strip reaches a little past now and grows in steps of 2 %: every bar is
    // laid out again once per step, not at every update of a long leg.
    const needed = (t1 - t0) / 1000;
    if (!(this.span >= needed && this.span <= needed * 1.05)) {
      this.span = needed * 1.02;
      this.track.style.setProperty("--span", String(this.span));
    }
    const t2 = t0 + this.span * 1000;
    const kids = this.track.children;
    if (bars.length !== kids.length || bars.some((b, i) => kids[i] !== b)) this.track.replaceChildren(...bars);
    // The time axis: start, middle and end of the strip.
    [t0, (t0 + t2) / 2, t2].forEach((time, i) => {
      const text = fmtClock(new Date(time).toISOString());
      if (this.axis.children[i].textContent !== text) this.axis.children[i].textContent = text;
    });
  },
  bar(id, className, color, text, label) {
    const b = document.createElement("button");
    b.type = "button";
    b.className = className;
    const fill = document.createElement("span");
    fill.className = "fill";
    if (color) fill.style.backgroundColor = color;
    fill.textContent = text;
    b.append(fill);
    // The name holds the visible words, so speech control finds the bar by them.
    b.setAttribute("aria-label", label);
    b.title = label;
    b.addEventListener("click", () => selectSegment(id));
    return b;
  },
};

export async function selectionChanged() {
  const leg = current("leg");
  const restoring = state.shownLeg === undefined && fromUrl.leg === state.selected.leg ? fromUrl.segment : null;
  state.shownLeg = state.selected.leg;
  $("#segments-section").hidden = !leg;
  $("#maps-section").hidden = !leg;
  $("#mode-panel").hidden = !leg;
  Live.subscribe();
  state.segment = null;
  state.segments = [];
  state.tracks = {};
  state.labels = {};
  state.shortLabels = {};
  state.openTakeOver = null;
  clearMaps(state.selected.leg);
  if (!leg) {
    Collector.refresh();
    renderSegments();
    return;
  }
  // The server answers a page's requests one after the other: the list first (it
  // is what the operator waits for; on a page load it came with the page), the
  // tracks next (drawn and fitted as they arrive), and what the first screen does
  // not need waits for both.
  try {
    await Promise.all([loadSegments(), loadTracks()]);
  } finally {
    Collector.refresh();
  }
  if (restoring && byId(state.segments, restoring)) selectSegment(restoring);
  else saveUrl();
  // The map image and overlay belong to the shift: kept when only the leg changes.
  const local = state.localMapOf === state.selected.shift ? null : loadLocalMap();
  await Promise.all([loadBasemaps(), local]);
  // A map image just received may have shown the local map.
  localMap.invalidate();
  if (local) localMap.fitAll();
}

export async function loadSegments() {
  const leg = state.selected.leg;
  const brought = take("segments", leg);
  // Until the server has spoken, what this browser kept at the cut is shown at
  // once; an answer read later than it (by the change feed's id) replaces it.
  const kept = Live.link === "live" ? null : keptLeg(leg);
  if (kept && !brought) showRows(kept);
  let answer = brought;
  try {
    // Rows and their labels in one read: the server works on one request at a time per page.
    answer ??= await api("GET", `legs/${leg}/segments/`, undefined, { root: CONFIG.guiApiRoot });
  } catch (err) {
    if (!(err instanceof TypeError) || Live.link === "live") throw err;
    answer = null;
  }
  if (leg !== state.selected.leg) return;
  const data = kept && (!answer || kept.last_event > answer.last_event) ? kept : answer;
  if (!data) return showNoHistory(leg);
  // A kept state is caught up from its own place in the feed, which may lie before the page's.
  if (data === kept) state.lastEventId = Math.min(state.lastEventId ?? kept.last_event, kept.last_event);
  showRows(data);
}

function showRows(data) {
  const empty = $("#segments-empty");
  if (empty.dataset.empty !== undefined) empty.textContent = empty.dataset.empty;
  state.segments = [];
  state.labels = {};
  state.shortLabels = {};
  applyRows(data, null);
}

/* A dead link and nothing kept of this leg in this browser: said so, and read once the link is back. */
function showNoHistory(leg) {
  const empty = $("#segments-empty");
  empty.dataset.empty ??= empty.textContent;
  empty.textContent = _("This device has kept nothing of this leg; its take-overs appear once the server is reached.");
  state.segments = [];
  renderSegments();
  Live.whenLive(() => {
    if (leg === state.selected.leg) Live.later("segments");
  });
}

/* A segment event, and the answer of a segment write, carry the rows the change
 * touched (events.api.serializers.touched_rows): they replace or join the list
 * without reading it again.  False when the event did not carry them, and the
 * caller re-reads. */
export function applySegments(e) {
  if (!e.segments || e.leg !== state.selected.leg) return false;
  applyRows(e);
  return true;
}

/* Rows with their labels and the leg's open take-over, as the server answers them. */
function applyRows(answer, changed = new Set(answer.segments.map((s) => s.id))) {
  answer.segments.forEach(putSegment);
  Object.assign(state.labels, answer.labels);
  Object.assign(state.shortLabels, answer.short_labels);
  state.openTakeOver = answer.open_take_over ?? null;
  renderSegments(changed);
  drawTakeOvers();
  keepShownLeg();
}

/* What the page shows of the leg, kept for a reload on a dead link (lastknown.js). */
function keepShownLeg() {
  const leg = state.selected.leg;
  if (!leg) return;
  keepLeg({
    leg,
    segments: state.segments,
    labels: state.labels,
    short_labels: state.shortLabels,
    open_take_over: state.openTakeOver,
    // Never older than the state it replaces: catching up from a kept state lowers lastEventId.
    last_event: Math.max(state.lastEventId ?? 0, keptLeg(leg)?.last_event ?? 0),
  });
}

/* A write through /gui/api/ answers with the row it wrote and every row it touched.
 * One described by `what` is kept on a dead link to be sent later (outbox.js):
 * then there is no row yet.  Ending a segment is not kept: sent later, it would
 * end it at the wrong time. */
async function segmentWrite(path, body, what, kept, timed = false) {
  const leg = state.selected.leg;
  const answer = what
    ? (await Outbox.write({ method: "POST", path, body, gui: true, what, kept, timed })).answer
    : await api("POST", path, body, { root: CONFIG.guiApiRoot });
  if (!answer) return null;
  if (leg === state.selected.leg) applyRows(answer);
  return answer.segment;
}

async function loadTracks() {
  const leg = state.selected.leg;
  const data = await showLegTracks(leg);
  if (leg !== state.selected.leg) return;
  state.tracks = data.segments;
  drawTakeOvers();
  renderSegments();
}

export function drawTakeOvers() {
  showTakeOvers(state.segments, state.tracks);
}

function visibleSegments() {
  const itoOnly = $("#ito-only").checked;
  // AUTO and unknown-mode masters and ITO reasons (children); an ITO master is shown through its children.
  return state.segments
    .filter((s) => (s.parent === null ? s.segment_type !== "ito" && !itoOnly : true))
    .sort((a, b) => (a.start < b.start ? 1 : a.start > b.start ? -1 : b.id - a.id));
}

/* The list shows the rows in view on a long leg (virtual-rows.js); `changed`
 * names the segments a message touched, whose rows alone are written again
 * (null: every rendered row, e.g. when durations or distances moved on). */
export function renderSegments(changed = null) {
  renderMode();
  updateSegmentButtons();
  Timeline.render();
  const rows = visibleSegments();
  $("#segments-empty").hidden = rows.length > 0 || !state.selected.leg;
  segmentList().show(rows, changed);
}

let list = null;
function segmentList() {
  list ??= new VirtualRows({ table: $("#segment-table"), scroller: $("#segment-table").closest(".table-wrap"), build: segmentRow, update: updateRow });
  return list;
}

function segmentCells(s) {
  const master = s.parent === null ? s.id : s.parent;
  const track = state.tracks[master];
  return [
    { text: shortLabel(s.id), title: _("%(label)s (database id %(id)s)", { label: segmentLabel(s.id), id: s.id }) },
    modeName(s.segment_type),
    // A reason kept in this browser (outbox.js) is shown until it is sent.
    s.parent === null ? "" : s.id in Outbox.keptReasons ? `${reasonName(Outbox.keptReasons[s.id])} (${_("not sent yet")})` : reasonName(s.ito_reason),
    { text: fmtClock(s.start), title: fmtTime(s.start) },
    s.end ? { text: fmtClock(s.end), title: fmtTime(s.end) } : "—",
    fmtDuration(s.start, s.end),
    fmtDistance(track ? track.distance_m : null),
    s.is_open ? _("open") : _("closed"),
  ];
}

function segmentRow(s) {
  const tr = document.createElement("tr");
  tr.dataset.id = s.id;
  // Focusable for the list's arrow keys (virtual-rows.js); the list itself is the tab stop.
  tr.tabIndex = -1;
  tr.append(...segmentCells(s).map(() => document.createElement("td")));
  updateRow(tr, s);
  const id = s.id;
  tr.addEventListener("click", () => selectSegment(id === state.segment ? null : id));
  tr.addEventListener("dblclick", () => {
    selectSegment(id);
    openSegmentDialog(id);
  });
  tr.addEventListener("keydown", (e) => {
    if (e.key === "Enter") {
      e.preventDefault();
      selectSegment(id);
      openSegmentDialog(id);
    } else if (e.key === " ") {
      e.preventDefault();
      selectSegment(id === state.segment ? null : id);
    }
  });
  return tr;
}

/* The row's words written again where they differ: the row keeps its node. */
function updateRow(tr, s) {
  const className = `${s.segment_type} ${s.parent === null ? "master" : "child"}${s.id === state.segment ? " selected" : ""}`;
  if (tr.className !== className) tr.className = className;
  segmentCells(s).forEach((c, i) => {
    const td = tr.cells[i];
    const text = typeof c === "object" ? c.text : c;
    const title = typeof c === "object" ? c.title : "";
    if (td.textContent !== text) td.textContent = text;
    if (td.title !== title) td.title = title;
  });
}

function selectSegment(id) {
  state.segment = id;
  saveUrl();
  updateSegmentButtons();
  Timeline.render();
  $$("#segment-table tbody tr[data-id]").forEach((tr) => tr.classList.toggle("selected", Number(tr.dataset.id) === id));
  // Chosen elsewhere (the timeline, a shared link): the list shows its row.
  if (id !== null) segmentList().reveal(id);
  const s = byId(state.segments, id);
  const master = s ? (s.parent === null ? s.id : s.parent) : null;
  gpsMap.select(master);
  localMap.select(master);
}

$("#ito-only").addEventListener("change", () => renderSegments());

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

/* Which robot this is, in every size: with two robots both may be on "Leg 1". */
function whom() {
  const [event, shift, leg] = ["event", "shift", "leg"].map(current);
  if (!event || !shift || !leg) return "";
  return `${vehicleName(shift.vehicle)} · ${event.location || _("test event #%(id)s", { id: event.id })} · ${_("Shift %(shift)s · Leg %(leg)s", { shift: shift.number, leg: leg.number })}`;
}

export function renderMode() {
  const panel = $("#mode-panel");
  const m = openMaster();
  const mode = m ? m.segment_type : "none";
  panel.dataset.mode = mode;
  $("#mode-whom").textContent = whom();
  // A dead link must not look live: what the page knows is shown as what it was.
  const lost = Live.lost();
  panel.dataset.link = lost === null ? "live" : "lost";
  const reasonless = m && m.segment_type === "ito" && !state.segments.some((c) => c.parent === m.id && c.is_open);
  if (lost !== null) {
    $("#mode-name").textContent = _("last known: %(mode)s, %(seconds)s s ago", { mode: m ? modeName(mode) : _("no open segment"), seconds: lost });
    $("#mode-since").textContent = `${m ? `${segmentLabel(m.id)} · ` : ""}${reasonless ? _("no open reason") + " · " : ""}${_("no word from the server, reconnecting")}`;
    return;
  }
  $("#mode-name").textContent = m ? modeName(mode) : _("No open segment");
  $("#mode-since").textContent = m ? _("for %(duration)s · %(segment)s", { duration: fmtDuration(m.start, null), segment: segmentLabel(m.id) }) + (reasonless ? " · " + _("no open reason") : "") : "";
}

/* Quick reasons annotate the leg's open take-over, which the server names;
 * an earlier take-over gets its reason in its dialog. */
function updateSegmentButtons() {
  const s = byId(state.segments, state.segment);
  const target = state.openTakeOver;
  $("#quick-target").textContent = target ? _("Reason for %(segment)s:", { segment: shortLabel(target) }) : _("No open take-over");
  for (const b of $$("[data-quick], #reason-apply")) {
    b.disabled = !CONFIG.canOperate || !target;
    b.title = target ? _("Give %(segment)s this reason", { segment: segmentLabel(target) }) : _("Reasons of earlier take-overs: Edit the row.");
  }
  // The robot's reason (params.reason_rules) waits for one tap to become the reason.
  const t = byId(state.segments, target);
  const suggested = $("#reason-suggested");
  const open = t && t.suggested_reason && t.unannotated ? t.suggested_reason : "";
  suggested.hidden = !open;
  suggested.dataset.reason = open;
  suggested.disabled = !CONFIG.canOperate || !open;
  suggested.textContent = open ? `${suggested.dataset.label}: ${reasonName(open)} ✓` : "";
  $("#segment-end").disabled = !CONFIG.canOperate || !(s && s.is_open);
  $("#segment-edit").disabled = !s;
}

function requireSegment() {
  if (!state.segment) throw new ApiError(_("Select a segment in the list first."));
  return state.segment;
}

async function setReason(key) {
  // The server picks the take-over (the robot may have started a new one a moment ago).
  const seen = state.openTakeOver;
  const what = _("%(reason)s for %(take_over)s", { reason: reasonName(key), take_over: segmentLabel(seen) });
  // Kept while offline, it names the take-over seen: another may be open by the time it is sent.
  const row = await segmentWrite(`legs/${state.selected.leg}/quick-reason/`, { reason: key }, what, { reason: key, take_over: seen });
  if (row) notice(_("Reason of %(segment)s set to %(reason)s.", { segment: segmentLabel(row.id), reason: reasonName(key) }));
}

$$("[data-quick]").forEach((b) => b.addEventListener("click", () => segmentAction(() => setReason(b.dataset.quick))));
$("#reason-suggested").addEventListener("click", () => segmentAction(() => setReason($("#reason-suggested").dataset.reason)));
$("#reason-apply").addEventListener("click", () => segmentAction(() => setReason($("#reason-any").value)));
$("#segment-new").addEventListener("click", () => segmentAction(async () => {
  const m = openMaster();
  if (m && m.segment_type === "auto") {
    const ok = await confirmDialog(_("The robot is in AUTO. Record a take-over (ITO) now?"), { yes: _("Record take-over"), no: _("Cancel"), warn: false });
    if (!ok) return;
  }
  const leg = current("leg");
  const child = await segmentWrite(`legs/${leg.id}/manual-segment/`, { uid: newUid() }, _("a new take-over in Leg %(number)s", { number: leg.number }), undefined, true);
  if (!child) return;
  selectSegment(child.id);
  notice(_("Take-over recorded."));
}));
$("#segment-end").addEventListener("click", () => segmentAction(async () => {
  const id = requireSegment();
  // Ending a master ends its reasons too: the answer brings them all.
  await segmentWrite(`segments/${id}/close/`, {});
  // Ending a reason leaves its take-over (the ITO run) open: the banner stays ITO, and says why.
  const m = openMaster();
  const still = m && m.segment_type === "ito" && byId(state.segments, id)?.parent === m.id;
  notice(still ? _("Ended the reason %(reason)s. The take-over %(take_over)s goes on (ITO) until the robot reports AUTO or you end %(short)s.", { reason: segmentLabel(id), take_over: segmentLabel(m.id), short: shortLabel(m.id) }) : _("Ended %(name)s.", { name: segmentLabel(id) }));
}));
$("#segment-edit").addEventListener("click", () => segmentAction(async () => openSegmentDialog(requireSegment())));
// The dialog's saves put their answers into the list (segment-dialog.js): shown once it closes.
$("#segment-dialog").addEventListener("close", () => renderSegments());

/* Distances come from the server (geodesic); the lines are drawn again from the
 * server's tracks when the feed said a track changed inside (a late batch) or
 * did not inline its points.  A read asked for while one runs follows it. */
export async function refreshDistances(redraw) {
  const leg = state.selected.leg;
  if (!leg) return;
  if (refreshDistances.busy) {
    // Points appended while a redraw is read may be missing from its answer: drawn again after it.
    refreshDistances.again = { redraw: redraw || refreshDistances.busy === "redraw" || Boolean(refreshDistances.again?.redraw) };
    return;
  }
  refreshDistances.busy = redraw ? "redraw" : "read";
  try {
    if (redraw) {
      const data = await loadLegTracks(leg);
      if (leg !== state.selected.leg) return;
      drawLegTracks(data);
      state.tracks = data.segments;
    } else {
      // The points came with the feed and are drawn: only the figures are read,
      // so the read costs the same on a long leg as on a fresh one.
      const data = await api("GET", `legs/${leg}/distances/`, undefined, { root: CONFIG.guiApiRoot });
      if (leg !== state.selected.leg) return;
      for (const [id, metres] of Object.entries(data.distances)) {
        state.tracks[id] ??= { gps: [], local: [], distance_m: null };
        state.tracks[id].distance_m = metres;
      }
    }
    renderSegments();
  } finally {
    refreshDistances.busy = false;
  }
  const again = refreshDistances.again;
  refreshDistances.again = null;
  if (again) await refreshDistances(again.redraw);
}

/* A live batch of positions of the leg on screen, as the server stored them:
 * usable points in driving order that follow the line's end, drawn at once;
 * or word that the segment's track changed, which is drawn again from the
 * server.  The distances follow from the server. */
export function appendPoses(e) {
  if (!onSelectedLeg(e)) return;
  const p = e.payload;
  if (p.changed || !p.points) {
    Live.later("tracks");
    return;
  }
  const map = e.kind === "poses" ? gpsMap : localMap;
  const pts = e.kind === "poses" ? p.points.map(([lon, lat]) => [lat, lon]) : p.points;
  map.appendPoints(p.segment, p.mode, pts);
  if (pts.length) showPosition(map, pts.at(-1), p.heading);
  const t = state.tracks[p.segment] || (state.tracks[p.segment] = { mode: p.mode, gps: [], local: [], distance_m: null });
  (e.kind === "poses" ? t.gps : t.local).push(...pts);
  Live.later("distances");
}
