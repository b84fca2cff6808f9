/* Test event, shift and leg: the pickers, and New, Edit, End, Re-open and
 * Delete for each level.  Choosing a leg hands over to segments.js. */
import { CONFIG, $, $$ } from "./dom.js";
import { ApiError, api, list } from "./api.js";
import { take } from "./bootstrap.js";
import { clearError, notice, showError } from "./feedback.js";
import { LEVELS, byId, current, saveUrl, state, vehicleName } from "./state.js";
import { fmtDay, fmtTime } from "./format.js";
import { confirmDialog, formDialog } from "./dialogs.js";
import { Live } from "./live.js";
import { Collector } from "./collector.js";
import { selectionChanged } from "./segments.js";

// A final test event (docs/report.md) is read-only for operators; the server decides.
function stateOf(row) {
  if (row.finalised) return "final";
  return row.is_open ? "open" : "closed";
}

function rowLabel(level, row) {
  const status = stateOf(row);
  if (level === "event") return `#${row.id} ${row.location || "(no location)"} · ${fmtDay(row.start)} · ${status}`;
  if (level === "shift") return `Shift ${row.number} · ${vehicleName(row.vehicle)} · ${fmtTime(row.start)} · ${status}`;
  return `Leg ${row.number} · ${fmtTime(row.start)} · ${status}`;
}

export async function loadCatalogues() {
  // Reasons name and colour segments; vehicles name shifts.  Dialogs read their own choices.
  const [reasons, vehicles] = await Promise.all([
    take("reasons") ?? list("ito-reasons/"),
    take("vehicles") ?? list("vehicles/"),
  ]);
  Object.assign(state.catalogue, { reasons, vehicles });
  const any = $("#reason-any");
  any.replaceChildren(...reasons.map((r) => new Option(r.short_description, r.key)));
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
  badge.textContent = row ? stateOf(row) : "";
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

/* The dialog of a level as the server defines it: fields, choices, and what a
 * new entry starts with (only unambiguous choices).  Read at each opening, so a
 * vehicle configured a minute ago is offered. */
async function formOf(level) {
  const forms = await api("GET", "forms/", undefined, { root: CONFIG.guiApiRoot });
  return forms[level];
}

/* Nothing is written until Save; Cancel leaves no empty entry behind. */
async function createLevel(level) {
  const form = await formOf(level);
  if (form.unavailable) throw new ApiError(form.unavailable);
  const parent = LEVELS[level].parent;
  formDialog({
    title: `New ${LEVELS[level].label}`,
    subtitle: "Created when you press Save.",
    specs: form.fields,
    values: form.initial,
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

async function editLevel(level) {
  const row = current(level);
  if (!row) return;
  const form = await formOf(level);
  const name = level === "event" ? `Test event #${row.id}` : level === "shift" ? `Shift ${row.number}` : `Leg ${row.number}`;
  formDialog({
    title: name,
    subtitle: `Started ${fmtTime(row.start)}${row.end ? `, ended ${fmtTime(row.end)}` : ""}`,
    specs: form.fields,
    values: row,
    save: async (body) => {
      await api("PATCH", `${LEVELS[level].path}${row.id}/`, body);
      await loadLevel(level);
      notice("Saved.");
    },
  });
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
