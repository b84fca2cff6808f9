/* Test event, shift and leg: the pickers, and New, Edit, End, Re-open and
 * Delete for each level.  Choosing a leg hands over to segments.js. */
import { CONFIG, $, $$ } from "./dom.js";
import { ApiError, api, list } from "./api.js";
import { take } from "./bootstrap.js";
import { clearError, notice, showError } from "./feedback.js";
import { LEVELS, byId, current, saveUrl, state, vehicleName } from "./state.js";
import { fmtDay, fmtTime } from "./format.js";
import { _, plural } from "./i18n.js";
import { confirmDialog, formDialog } from "./dialogs.js";
import { Live } from "./live.js";
import { Collector } from "./collector.js";
import { selectionChanged } from "./segments.js";
import { TestPlan } from "./testplan.js";

// A final test event (docs/report.md) is read-only for operators; the server decides.
function stateOf(row) {
  if (row.finalised) return _("final");
  return row.is_open ? _("open") : _("closed");
}

function rowLabel(level, row) {
  const status = stateOf(row);
  if (level === "event") return `#${row.id} ${row.location || _("(no location)")} · ${fmtDay(row.start)} · ${status}`;
  if (level === "shift") return `${_("Shift %(number)s", { number: row.number })} · ${vehicleName(row.vehicle)} · ${fmtTime(row.start)} · ${status}`;
  return `${_("Leg %(number)s", { number: row.number })} · ${fmtTime(row.start)} · ${status}`;
}

export async function loadCatalogues() {
  // Reasons name and colour segments; vehicles name shifts.  Dialogs read their own choices.
  const [reasons, vehicles] = await Promise.all([
    take("reasons") ?? list("ito-reasons/"),
    take("vehicles") ?? list("vehicles/"),
  ]);
  Object.assign(state.catalogue, { reasons, vehicles });
  const any = $("#reason-any");
  any.replaceChildren(...reasons.map((r) => new Option(r.label, r.key)));
}

export async function loadLevel(level, keepSelection = true) {
  const info = LEVELS[level];
  const select = $(`#pick-${level}`);
  const parent = info.parent ? state.selected[info.parent] : null;
  let rows = [];
  if (!info.parent) rows = take(level) ?? (await list(info.path));
  else if (parent) rows = take(level, parent) ?? (await list(info.path, { [info.parentField]: parent }));
  // Newest first, whatever order the server uses.
  rows.sort((a, b) => (a.start < b.start ? 1 : a.start > b.start ? -1 : b.id - a.id));
  state.rows[level] = rows;
  let chosen = keepSelection && byId(rows, state.selected[level]) ? state.selected[level] : null;
  if (chosen === null && rows.length === 1) chosen = rows[0].id; // one child: take it
  const placeholder = new Option(rows.length ? info.choose() : info.none(), "");
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
  else {
    TestPlan.later();
    if (state.selected.leg !== state.shownLeg) await selectionChanged();
    else {
      // Same leg as before: only the labels and states changed, keep the drawing.
      Live.subscribe();
      Collector.refresh();
    }
  }
}

/* "final, amended 2 times": the server counts the amendments (the report lists them). */
async function showAmendments(row, badge) {
  const { count } = await api("GET", `reports/amendments/${row.id}/`);
  if (count && current("event") === row) badge.textContent = plural(ngettext("final, amended %(count)s time", "final, amended %(count)s times", count), count);
}

function updateLevelState(level) {
  const row = current(level);
  const badge = $(`[data-state="${level}"]`);
  badge.textContent = row ? stateOf(row) : "";
  badge.className = "state" + (row ? (row.is_open ? " open" : " closed") : "");
  if (level === "event" && row && row.finalised) showAmendments(row, badge).catch(showError);
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
  // Which rows re-open is the server's rule (events.services.logs.may_reopen).
  const reopen = Boolean(row && row.may_reopen);
  setBtn("end", Boolean(row && row.is_open), !reopen);
  setBtn("reopen", reopen, reopen);
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
      } else {
        TestPlan.later();
        await selectionChanged();
      }
    } catch (err) {
      showError(err);
    }
  });
}

/* The dialog of a level as the server defines it: fields, choices, and what a
 * new entry starts with (only unambiguous choices).  Read at each opening, so a
 * vehicle configured a minute ago is offered. */
async function formOf(level) {
  // The leg dialog offers the selected test event's test cases (the server's list).
  const event = state.selected.event ? `?event=${state.selected.event}` : "";
  const forms = await api("GET", `forms/${event}`, undefined, { root: CONFIG.guiApiRoot });
  return forms[level];
}

// How long End and New leg wait for the server to say what they end.
const ASK_MS = 2000;

/* What `action` on row `id` would end, as the server reads it (nothing is
 * written), as lines for the confirmation; none when it ends nothing that
 * a robot logs into. */
async function endingLines(action, id) {
  // Without the server's answer nothing can be asked, so nothing is ended; a dead
  // or half-open link is said at once, not after the browser gives up.
  const noAnswer = () => new ApiError(_("The server does not answer, so it cannot say what this ends: nothing was ended. Try again when the connection is back."), 0);
  if (!["live", "connecting"].includes(Live.link)) throw noAnswer();
  let e;
  try {
    e = await api("GET", `ending/?action=${action}&id=${id}`, undefined, { root: CONFIG.guiApiRoot, signal: AbortSignal.timeout(ASK_MS) });
  } catch (err) {
    if (err instanceof ApiError) throw err;
    throw noAnswer();
  }
  const lines = [];
  const names = (rows) => rows.map((r) => r.name).join(", ");
  if (e.vehicles.length) {
    const whose = e.vehicles.map((v) => v.name).join(", ");
    lines.push(e.logging_stops ? _("Logging stops on: %(vehicles)s. The robots store nothing until a new leg is started and logging is switched on.", { vehicles: whose }) : _("Logging goes on into the new leg: %(vehicles)s.", { vehicles: whose }));
  }
  if (e.shifts.length) lines.push(plural(ngettext("%(count)s shift ends: %(names)s", "%(count)s shifts end: %(names)s", e.shifts.length), e.shifts.length, { names: names(e.shifts) }));
  if (e.legs.length) lines.push(plural(ngettext("%(count)s leg ends: %(names)s", "%(count)s legs end: %(names)s", e.legs.length), e.legs.length, { names: names(e.legs) }));
  if (e.take_overs.length) lines.push(plural(ngettext("%(count)s open take-over ends: %(names)s", "%(count)s open take-overs end: %(names)s", e.take_overs.length), e.take_overs.length, { names: names(e.take_overs) }));
  return lines;
}

/* Asks before `action` when it ends anything; false when the operator keeps it. */
async function askBeforeEnding(action, id, question, yes) {
  const lines = await endingLines(action, id);
  if (!lines.length && action === "new-leg") return true;
  return confirmDialog(question, { yes, no: _("Cancel"), warn: false, items: lines });
}

/* Nothing is written until Save; Cancel leaves no empty entry behind. */
async function createLevel(level) {
  const form = await formOf(level);
  if (form.unavailable) throw new ApiError(form.unavailable);
  const parent = LEVELS[level].parent;
  formDialog({
    title: LEVELS[level].newTitle(),
    subtitle: _("Created when you press Save."),
    specs: form.fields,
    values: form.initial,
    save: async (body) => {
      if (parent) body[LEVELS[level].parentField] = state.selected[parent];
      // The server ends a vehicle's other open shift (its rule); the operator is asked first.
      // A new leg ends the shift's open leg (the server's rule): asked first, naming it.
      if (level === "leg" && !(await askBeforeEnding("new-leg", body.shift, _("Start a new leg? This ends the open leg of this shift."), _("End it and create")))) return false;
      const ending = level === "shift" && body.vehicle ? await list(LEVELS.shift.path, { vehicle: body.vehicle, open: "true" }) : [];
      if (ending.length) {
        const which = ending.map((r) => _("Shift %(number)s (started %(start)s)", { number: r.number, start: fmtTime(r.start) })).join(", ");
        const question = _("%(vehicle)s still has %(shifts)s open. Saving ends it. Create the new shift?", { vehicle: vehicleName(body.vehicle), shifts: which });
        if (!(await confirmDialog(question, { yes: _("End it and create"), no: _("Cancel"), warn: false }))) return false;
      }
      const row = await api("POST", LEVELS[level].path, body);
      state.selected[level] = row.id;
      const child = LEVELS[level].child;
      if (child) state.selected[child] = null;
      await loadLevel(level);
      const ended = ending.length ? " " + _("%(shifts)s of %(vehicle)s ended.", { shifts: ending.map((r) => _("Shift %(number)s", { number: r.number })).join(", "), vehicle: vehicleName(body.vehicle) }) : "";
      notice(LEVELS[level].created() + ended);
    },
  });
}

async function editLevel(level) {
  const row = current(level);
  if (!row) return;
  const form = await formOf(level);
  const name = level === "event" ? _("Test event #%(id)s", { id: row.id }) : level === "shift" ? _("Shift %(number)s", { number: row.number }) : _("Leg %(number)s", { number: row.number });
  formDialog({
    title: name,
    subtitle: row.end ? _("Started %(start)s, ended %(end)s", { start: fmtTime(row.start), end: fmtTime(row.end) }) : _("Started %(start)s", { start: fmtTime(row.start) }),
    specs: form.fields,
    values: row,
    save: async (body) => {
      await api("PATCH", `${LEVELS[level].path}${row.id}/`, body);
      await loadLevel(level);
      notice(_("Saved."));
    },
  });
}

function nameOf(level, row) {
  if (level === "event") return _("test event #%(id)s (%(location)s)", { id: row.id, location: row.location || _("no location") });
  if (level === "shift") return _("shift %(number)s", { number: row.number });
  return _("leg %(number)s", { number: row.number });
}

function deleteQuestion(level, row) {
  const name = nameOf(level, row);
  if (level === "event") return _("Delete %(name)s with all its shifts, legs, segments, notes and images?", { name });
  if (level === "shift") return _("Delete %(name)s with all its legs, segments, notes, images and maps?", { name });
  return _("Delete %(name)s with all its segments, notes and images?", { name });
}

async function levelAction(level, action) {
  const row = current(level);
  if (action === "new") return createLevel(level);
  if (action === "edit") return editLevel(level);
  if (!row) return;
  if (action === "delete") {
    if (!(await confirmDialog(deleteQuestion(level, row)))) return;
    await api("DELETE", `${LEVELS[level].path}${row.id}/`);
    state.selected[level] = null;
    await loadLevel(level, true);
    return notice(_("Deleted %(name)s.", { name: nameOf(level, row) }));
  }
  // The server stops logging into what ends (one rule, in its services); it says
  // beforehand what that will be, and the operator is asked.
  if (action === "end") {
    const question = _("End %(name)s?", { name: nameOf(level, row) });
    if (!(await askBeforeEnding(`end-${level}`, row.id, question, _("End %(name)s", { name: nameOf(level, row) })))) return;
    await api("POST", `${LEVELS[level].path}${row.id}/close/`, {});
  }
  if (action === "reopen") await api("POST", `${LEVELS[level].path}${row.id}/reopen/`, {});
  await loadLevel(level);
  return notice(action === "end" ? _("Ended %(name)s.", { name: nameOf(level, row) }) : _("Re-opened."));
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
