/* Black-box snapshots (MCAP files of the robot's raw messages around a
 * take-over or a request) in the segment dialog: what each holds, and a
 * download.  The collector writes them; the API lists and serves them. */
import { $ } from "./dom.js";
import { _ } from "./i18n.js";
import { list } from "./api.js";
import { fmtClock, fmtNumber } from "./format.js";

const box = $("#segment-dialog .snapshots");
let shownMaster = null;

function fmtSize(bytes) {
  if (bytes >= 1024 * 1024) return `${fmtNumber(bytes / 1024 / 1024, 1)} MB`;
  return `${Math.max(1, Math.round(bytes / 1024))} kB`;
}

function snapshotItem(r) {
  const li = document.createElement("li");
  const name = document.createElement("div");
  name.className = "name";
  name.textContent = r.name;
  const meta = document.createElement("div");
  meta.className = "meta";
  const why = r.reason ? ` · ${r.reason}` : "";
  meta.textContent = `${fmtClock(r.start)}–${fmtClock(r.end)} (${Math.round(r.duration)} s) · ${fmtSize(r.size)}${why}`;
  const topics = document.createElement("div");
  topics.className = "topics";
  topics.textContent = Object.entries(r.topics)
    .map(([topic, t]) => `${topic} (${t.count})`)
    .join(", ");
  topics.title = Object.entries(r.topics)
    .map(([topic, t]) => `${topic}: ${t.count} × ${t.type}`)
    .join("\n");
  const download = document.createElement("a");
  download.className = "button";
  download.href = r.file;
  download.setAttribute("download", r.name);
  download.textContent = _("Download");
  download.setAttribute("aria-label", _("Download %(name)s", { name: r.name }));
  li.append(name, meta, topics, download);
  return li;
}

/* The snapshots of a master segment (those of a reason are its master's). */
export async function loadSnapshots(master) {
  shownMaster = master;
  const rows = await list("recordings/", { segment: master });
  if (master === shownMaster) showSnapshots(master, rows);
}

export function showSnapshots(master, rows) {
  shownMaster = master;
  if (!rows.length) {
    const li = document.createElement("li");
    li.className = "muted";
    li.textContent = _("No snapshots.");
    box.replaceChildren(li);
    return;
  }
  box.replaceChildren(...rows.map(snapshotItem));
}

/* A snapshot was stored or deleted somewhere: redraw if the dialog shows one. */
export async function refreshSnapshots() {
  if (shownMaster !== null && box.closest("dialog").open) await loadSnapshots(shownMaster);
}
