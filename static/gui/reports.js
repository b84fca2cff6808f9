/* Reports and exports of the selected test event. */
import { CONFIG, $ } from "./dom.js";
import { api } from "./api.js";
import { showError } from "./feedback.js";
import { current } from "./state.js";
import { fmtTime } from "./format.js";
import { buildField } from "./dialogs.js";

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
