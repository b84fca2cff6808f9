/* The segment dialog: annotation of a take-over reason, notes, images and
 * black-box snapshots (snapshots.js). */
import { CONFIG, $, $$ } from "./dom.js";
import { api, list } from "./api.js";
import { notice, showError } from "./feedback.js";
import { byId, putSegment, segmentLabel, state } from "./state.js";
import { fmtTime } from "./format.js";
import { confirmDialog } from "./dialogs.js";
import { showSnapshots } from "./snapshots.js";

const segmentDialog = $("#segment-dialog");
export let dialogSegment = null;

export async function openSegmentDialog(id) {
  // The list's row is the same record (kept current by the change feed): no extra read.
  const s = byId(state.segments, id) || (await api("GET", `segments/${id}/`));
  dialogSegment = s;
  const errorBox = $(".dialog-error", segmentDialog);
  errorBox.hidden = true;
  const kind = s.segment_type === "ito" ? (s.parent === null ? "ITO (take-over)" : "ITO reason") : "AUTO";
  $(".title", segmentDialog).textContent = `${segmentLabel(s.id)} · ${kind}`;
  $(".subtitle", segmentDialog).textContent = `Start ${fmtTime(s.start)} · End ${s.end ? fmtTime(s.end) : "still open"}`;
  const form = $("#annotation-form");
  form.elements.ito_reason.replaceChildren(...state.catalogue.reasons.map((r) => new Option(r.short_description, r.key)));
  form.elements.ito_reason.value = s.ito_reason || "unassigned";
  for (const f of ["obstacle", "lighting", "slope", "location_type"]) form.elements[f].value = s[f] || "";
  form.elements.initiator.value = s.initiator || "safety_driver";
  form.elements.severity.value = s.severity || "not_applicable";
  form.elements.change_reason.value = "";
  const history = $(".history", segmentDialog);
  history.open = false;
  $(".history-list", history).replaceChildren();
  // Annotation belongs to take-over reasons; the server says so too if tried elsewhere.
  form.hidden = s.parent === null;
  $$("input, select, button", form).forEach((el) => (el.disabled = !CONFIG.canOperate));
  $$(".op-block", segmentDialog).forEach((el) => (el.hidden = !CONFIG.canOperate));
  // One read for notes, images and snapshots: three would queue one behind the other.
  const data = await api("GET", `segments/${s.id}/attachments/`, undefined, { root: CONFIG.guiApiRoot });
  if (dialogSegment !== s) return;
  showNotes(data.notes);
  showImages(data.images);
  showSnapshots(data.master, data.recordings);
  if (!segmentDialog.open) segmentDialog.showModal();
}

$(".close", segmentDialog).addEventListener("click", () => segmentDialog.close());
// segments.js redraws the list when the dialog closes.
segmentDialog.addEventListener("close", () => {
  dialogSegment = null;
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
  for (const f of ["ito_reason", "obstacle", "lighting", "slope", "initiator", "severity", "location_type"]) {
    body[f] = form.elements[f].value;
  }
  const reason = form.elements.change_reason.value.trim();
  putSegment(await api("PATCH", `segments/${dialogSegment.id}/`, body, { reason }));
  notice(`${segmentLabel(dialogSegment.id)} saved.`);
}));

// The change history is read when it is opened: most dialogs never show it.
$(".history", segmentDialog).addEventListener("toggle", dialogAction(async (e) => {
  if (!e.target.open || !dialogSegment) return;
  const entries = await api("GET", `segments/${dialogSegment.id}/history/`);
  $(".history-list", segmentDialog).replaceChildren(...entries.map(historyItem));
}));

function historyItem(entry) {
  const li = document.createElement("li");
  const changes = entry.changes.map((c) => `${c.field}: ${c.before ?? "—"} → ${c.after ?? "—"}`).join("; ");
  const why = entry.reason ? ` (${entry.reason})` : "";
  li.textContent = `${fmtTime(entry.at)} · ${entry.author} via ${entry.channel} · ${entry.kind}${changes ? ": " + changes : ""}${why}`;
  return li;
}

export async function loadNotes({ keepEditing = false } = {}) {
  if (!dialogSegment) return;
  const notes = await list("notes/", { segment: dialogSegment.id });
  // Checked after the fetch: the operator may have started editing meanwhile.
  if (keepEditing && $("textarea", $(".notes", segmentDialog))) return;
  showNotes(notes);
}

function showNotes(notes) {
  const ul = $(".notes", segmentDialog);
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

export async function loadImages() {
  if (!dialogSegment) return;
  showImages(await list("images/", { segment: masterOf(dialogSegment) }));
}

function showImages(images) {
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
