/* The segment dialog: annotation of a take-over reason, notes, images and
 * black-box snapshots (snapshots.js). */
import { CONFIG, $, $$ } from "./dom.js";
import { _ } from "./i18n.js";
import { api, list } from "./api.js";
import { Outbox, newUid } from "./outbox.js";
import { notice, showError } from "./feedback.js";
import { byId, modeName, putSegment, segmentLabel, state } from "./state.js";
import { fmtNumber, fmtTime } from "./format.js";
import { confirmDialog } from "./dialogs.js";
import { showSnapshots } from "./snapshots.js";

const segmentDialog = $("#segment-dialog");
export let dialogSegment = null;
// A reason's fields, as the server names them (Segment.NO_ANNOTATION, in the page's CONFIG).
const ANNOTATION = Object.keys(CONFIG.annotation);
// The annotation as the dialog showed it: Save sends only what the operator changed.
let shownValues = {};

/* The segment `s` with the writes kept for it in this browser applied, oldest
 * first (a quick reason for it, edits of it), so that an edit made offline
 * after a quick reason starts from that reason; `kept`: whether any applied. */
function composed(s, pending) {
  const row = { ...s };
  let kept = false;
  for (const e of pending) {
    if (e.gui && e.path === `legs/${s.leg}/quick-reason/` && e.body.take_over === s.id) {
      row.ito_reason = e.body.reason;
      kept = true;
    } else if (e.method === "PATCH" && !e.gui && e.path === `segments/${s.id}/`) {
      Object.assign(row, e.body);
      kept = true;
    }
  }
  return { row, kept };
}

export async function openSegmentDialog(id) {
  // The list's row is the same record (kept current by the change feed): no extra read.
  const s = byId(state.segments, id) || (await api("GET", `segments/${id}/`));
  dialogSegment = s;
  const errorBox = $(".dialog-error", segmentDialog);
  errorBox.hidden = true;
  const kind = s.segment_type === "ito" ? (s.parent === null ? _("ITO (take-over)") : _("ITO reason")) : modeName(s.segment_type);
  $(".title", segmentDialog).textContent = `${segmentLabel(s.id)} · ${kind}`;
  // Set when the robot's mode message had no stamp: the switch lies within this interval.
  const uncertain = s.start_uncertainty > 0 ? " " + _("(switched up to %(seconds)s s earlier; the robot's mode message has no time stamp)", { seconds: fmtNumber(s.start_uncertainty, 1) }) : "";
  $(".subtitle", segmentDialog).textContent = _("Start %(start)s · End %(end)s", { start: fmtTime(s.start) + uncertain, end: s.end ? fmtTime(s.end) : _("still open") });
  const form = $("#annotation-form");
  // What the server has, with what this browser keeps to send for it on top.
  const { row, kept } = composed(s, await Outbox.pending().catch(() => []));
  if (dialogSegment !== s) return;
  form.elements.ito_reason.replaceChildren(...state.catalogue.reasons.map((r) => new Option(r.label, r.key)));
  // A take-over reason always names one (Unassigned until annotated); a master shows no form.
  form.elements.ito_reason.value = row.ito_reason || "";
  for (const f of ANNOTATION) if (f !== "ito_reason") form.elements[f].value = row[f] || CONFIG.annotation[f];
  form.elements.change_reason.value = "";
  shownValues = Object.fromEntries(ANNOTATION.map((f) => [f, form.elements[f].value]));
  $(".kept-changes", segmentDialog).hidden = !kept;
  const history = $(".history", segmentDialog);
  history.open = false;
  $(".history-list", history).replaceChildren();
  // Annotation belongs to take-over reasons; the server says so too if tried elsewhere.
  form.hidden = s.parent === null;
  $$("input, select, button", form).forEach((el) => (el.disabled = !CONFIG.canOperate));
  $$(".op-block", segmentDialog).forEach((el) => (el.hidden = !CONFIG.canOperate));
  // One read for notes, images and snapshots: three would queue one behind the other.
  let data = null;
  try {
    data = await api("GET", `segments/${s.id}/attachments/`, undefined, { root: CONFIG.guiApiRoot });
  } catch (err) {
    // On a dead link the dialog still opens: notes and photos made now are kept (outbox.js).
    if (!(err instanceof TypeError)) throw err;
  }
  if (dialogSegment !== s) return;
  if (data) {
    showNotes(data.notes);
    showImages(data.images);
    showSnapshots(data.master, data.recordings);
  } else {
    errorBox.textContent = _("The server cannot be reached: the notes and images stored cannot be shown now. What you add is kept in this browser and sent later.");
    errorBox.hidden = false;
  }
  if (!segmentDialog.open) {
    keepBannerInSight();
    segmentDialog.showModal();
  }
}

/* The dialog opens below the mode banner when the banner is on screen, so the
 * mode (a robot switching while a note is typed) stays in sight. */
function keepBannerInSight() {
  const banner = $("#mode-panel .mode-now").getBoundingClientRect();
  const below = banner.height && banner.top >= 0 && banner.bottom < window.innerHeight / 2 ? Math.ceil(banner.bottom) + 6 : null;
  segmentDialog.style.marginTop = below === null ? "" : `${below}px`;
  segmentDialog.style.maxHeight = below === null ? "" : `calc(100vh - ${below + 6}px)`;
  segmentDialog.classList.toggle("under-banner", below !== null);
}

$(".close", segmentDialog).addEventListener("click", () => segmentDialog.close());
// segments.js redraws the list when the dialog closes.
segmentDialog.addEventListener("close", () => {
  dialogSegment = null;
});

/* The button that started an action stays off until it has answered: a second
 * tap on a slow link does not send the same note twice. */
function dialogAction(fn) {
  return async (e) => {
    if (e) e.preventDefault();
    const errorBox = $(".dialog-error", segmentDialog);
    errorBox.hidden = true;
    const button = e && (e.submitter || (e.currentTarget instanceof HTMLButtonElement ? e.currentTarget : null));
    if (button) button.disabled = true;
    try {
      await fn(e);
    } catch (err) {
      showError(err, errorBox);
    } finally {
      if (button) button.disabled = !CONFIG.canOperate;
    }
  };
}

$("#annotation-form").addEventListener("submit", dialogAction(async () => {
  const form = $("#annotation-form");
  const body = {};
  for (const f of ANNOTATION) {
    if (form.elements[f].value !== shownValues[f]) body[f] = form.elements[f].value;
  }
  const id = dialogSegment.id;
  if (!Object.keys(body).length) return notice(_("Nothing changed in %(segment)s.", { segment: segmentLabel(id) }));
  const reason = form.elements.change_reason.value.trim();
  const { answer } = await Outbox.write({ method: "PATCH", path: `segments/${id}/`, body, reason, what: _("the edit of %(segment)s", { segment: segmentLabel(id) }) });
  Object.assign(shownValues, body);
  if (!answer) return;
  putSegment(answer);
  notice(_("%(segment)s saved.", { segment: segmentLabel(id) }));
}));

// The change history is read when it is opened: most dialogs never show it.
$(".history", segmentDialog).addEventListener("toggle", dialogAction(async (e) => {
  if (!e.target.open || !dialogSegment) return;
  const entries = await api("GET", `segments/${dialogSegment.id}/history/`);
  $(".history-list", segmentDialog).replaceChildren(...entries.map(historyItem));
}));

function historyItem(entry) {
  const li = document.createElement("li");
  const changes = entry.changes.map((c) => `${c.field_name}: ${c.before ?? "—"} → ${c.after ?? "—"}`).join("; ");
  const why = entry.reason ? ` (${entry.reason})` : "";
  const who = _("%(when)s · %(author)s via %(channel)s · %(kind)s", {
    when: fmtTime(entry.at), author: entry.author, channel: entry.channel_text, kind: entry.kind_text,
  });
  li.textContent = `${who}${changes ? ": " + changes : ""}${why}`;
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
    li.textContent = _("No notes yet.");
    ul.replaceChildren(li);
    return;
  }
  ul.replaceChildren(...notes.map((n) => {
    const li = document.createElement("li");
    li.dataset.id = n.id;
    const meta = document.createElement("div");
    meta.className = "meta";
    const edited = n.edited && n.edited !== n.created ? ` · ${_("edited %(when)s", { when: fmtTime(n.edited) })}` : "";
    meta.textContent = `${n.author_name || _("unknown author")} · ${fmtTime(n.created)}${edited}`;
    const text = document.createElement("div");
    text.className = "text";
    text.textContent = n.text;
    li.append(meta, text);
    if (CONFIG.canOperate) {
      const edit = document.createElement("button");
      edit.type = "button";
      edit.textContent = _("Edit");
      edit.addEventListener("click", () => editNote(li, n));
      const del = document.createElement("button");
      del.type = "button";
      del.textContent = _("Delete");
      del.className = "danger";
      del.addEventListener("click", dialogAction(async () => {
        if (!(await confirmDialog(_("Delete this note by %(author)s?", { author: n.author_name || _("unknown author") })))) return;
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
  area.setAttribute("aria-label", _("Note text"));
  const save = document.createElement("button");
  save.type = "button";
  save.className = "primary";
  save.textContent = _("Save note");
  save.addEventListener("click", dialogAction(async () => {
    await api("PATCH", `notes/${note.id}/`, { text: area.value });
    await loadNotes();
  }));
  const cancel = document.createElement("button");
  cancel.type = "button";
  cancel.textContent = _("Cancel");
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
  const body = { uid: newUid(), segment: dialogSegment.id, text: form.elements.text.value };
  if (CONFIG.personnel) body.author = CONFIG.personnel;
  const { answer } = await Outbox.write({ method: "POST", path: "notes/", body, what: _("a note on %(segment)s", { segment: segmentLabel(dialogSegment.id) }) });
  form.reset();
  if (answer) await loadNotes();
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
    p.textContent = _("No images yet.");
    box.replaceChildren(p);
    return;
  }
  box.replaceChildren(...images.map((im) => {
    const fig = document.createElement("figure");
    const img = document.createElement("img");
    img.src = im.url || im.image;
    img.alt = im.description || _("Image %(id)s", { id: im.id });
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
      del.textContent = _("Delete");
      del.addEventListener("click", dialogAction(async () => {
        if (!(await confirmDialog(_("Delete this image?")))) return;
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
    const fields = { uid: newUid(), segment: masterOf(dialogSegment), description: _("Uploaded by %(user)s", { user: CONFIG.user }) };
    const form = { fields, fileField: "image", file, fileName: file.name };
    const { answer } = await Outbox.write({ method: "POST", path: "images/", form, what: _("a photo of %(segment)s", { segment: segmentLabel(dialogSegment.id) }) });
    input.value = "";
    if (!answer) return;
    await loadImages();
    notice(_("Image uploaded."));
  })),
);
