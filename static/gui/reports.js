/* Reports and exports of the selected test event. */
import { CONFIG, $ } from "./dom.js";
import { _ } from "./i18n.js";
import { api } from "./api.js";
import { showError } from "./feedback.js";
import { current } from "./state.js";
import { fmtNumber, fmtTime } from "./format.js";
import { buildField } from "./dialogs.js";

$("#open-reports").addEventListener("click", () => Reports.open().catch(showError));

/* A report job's state, as the page words it. */
const JOB_STATUS = { queued: _("queued"), running: _("running"), done: _("done"), failed: _("failed") };
const EXPORTS = [
  ["segments.csv", _("Segments (CSV)")],
  ["tracks.geojson", _("Tracks (GeoJSON)")],
  ["tracks.gpx", _("Tracks (GPX)")],
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
      p.textContent = _("Select a test event first.");
      body.append(p, this.verifyForm());
    } else {
      // The form's fields are the server's (gui/api/forms/, "report").
      const forms = await api("GET", "forms/", undefined, { root: CONFIG.guiApiRoot });
      body.append(this.downloads(event), this.form(event, forms.report), Object.assign(document.createElement("div"), { id: "report-list" }), this.verifyForm());
      await this.refresh(event);
    }
    if (!d.open) d.showModal();
  },
  downloads(event) {
    const p = document.createElement("p");
    p.append(`${_("Data of test event #%(id)s:", { id: event.id })} `);
    const archive = [`test-events/${event.id}/archive/`, _("Everything (FTT archive, ZIP)")];
    for (const [path, label] of [...EXPORTS.map(([f, l]) => [`reports/exports/${event.id}/${f}`, l]), archive]) {
      const a = document.createElement("a");
      a.href = CONFIG.apiRoot + path;
      a.textContent = label;
      a.setAttribute("download", "");
      p.append(a, " ");
    }
    return p;
  },
  form(event, { fields, initial }) {
    const form = document.createElement("form");
    form.id = "report-form";
    const saved = JSON.parse(localStorage.getItem("ftt.reportFields") || "{}");
    const scope = this.scopeField();
    form.append(scope.field);
    for (const spec of fields) form.append(buildField(spec, saved[spec.name] ?? initial[spec.name] ?? ""));
    const go = document.createElement("button");
    go.type = "submit";
    go.className = "primary";
    go.textContent = _("Generate report");
    go.disabled = !CONFIG.canOperate;
    form.append(go);
    form.addEventListener("submit", async (e) => {
      e.preventDefault();
      const errorBox = $("#reports-dialog .dialog-error");
      errorBox.hidden = true;
      const values = Object.fromEntries(fields.map((s) => [s.name, form.elements[s.name].value]));
      localStorage.setItem("ftt.reportFields", JSON.stringify(values));
      const options = {};
      for (const spec of fields) {
        const raw = values[spec.name];
        if (spec.type === "textarea") options[spec.name] = raw.split("\n").map((l) => l.trim()).filter(Boolean);
        else if (spec.type === "select" && ["true", "false"].includes(raw)) options[spec.name] = raw === "true";
        else if (spec.type === "number") {
          // Empty means "the server's default"; whatever else was typed goes as a
          // number or as text, and the server says what is wrong.
          if (raw.trim() !== "") options[spec.name] = Number.isFinite(Number(raw)) ? Number(raw) : raw.trim();
        } else options[spec.name] = raw;
      }
      try {
        await api("POST", "reports/", { test_event: event.id, ...scope.chosen(form), options });
        await this.refresh(event);
      } catch (err) {
        showError(err, errorBox);
      }
    });
    return form;
  },
  /* Is a report (PDF or JSON) still true to the data? The server checks (the
   * answer of ftt_report --verify); the page shows its answer. */
  verifyForm() {
    const form = document.createElement("form");
    form.id = "verify-form";
    const h = document.createElement("h3");
    h.textContent = _("Verify a report");
    const label = document.createElement("label");
    label.append(`${_("Report file (PDF or JSON)")} `);
    const file = Object.assign(document.createElement("input"), { type: "file", name: "file", accept: ".pdf,.json,application/pdf,application/json" });
    label.append(file);
    const go = Object.assign(document.createElement("button"), { type: "submit", textContent: _("Verify") });
    const answer = Object.assign(document.createElement("div"), { className: "verify-answer" });
    answer.setAttribute("role", "status");
    form.append(h, label, " ", go, answer);
    form.addEventListener("submit", async (e) => {
      e.preventDefault();
      const errorBox = $("#reports-dialog .dialog-error");
      errorBox.hidden = true;
      answer.replaceChildren();
      const data = new FormData();
      if (file.files[0]) data.append("file", file.files[0]);
      try {
        answer.replaceChildren(this.verdict(await api("POST", "reports/verify/", data)));
      } catch (err) {
        showError(err, errorBox);
      }
    });
    return form;
  },
  verdict({ ok, message, changes }) {
    const box = document.createElement("div");
    const p = document.createElement("p");
    p.className = ok ? "verify-ok" : "verify-changed";
    p.textContent = `${ok ? _("OK") : _("CHANGED")}: ${message}`;
    box.append(p);
    if (changes.length) {
      const ul = document.createElement("ul");
      for (const c of changes) {
        const li = document.createElement("li");
        const who = c.by || _("FTT");
        const values = { record: c.record, at: fmtTime(c.at), who, channel: c.channel };
        const line =
          c.kind === "deleted"
            ? _("%(record)s deleted %(at)s by %(who)s via %(channel)s", values)
            : c.kind === "created"
              ? _("%(record)s created %(at)s by %(who)s via %(channel)s", values)
              : _("%(record)s changed %(at)s by %(who)s via %(channel)s", values);
        li.textContent = line + (c.reason ? ` (${c.reason})` : "");
        ul.append(li);
      }
      box.append(ul);
    }
    return box;
  },
  /* The whole test event, or the shift or leg selected when the dialog opened
   * (the narrowest by default); the server checks that they belong together. */
  scopeField() {
    const shift = current("shift");
    const leg = shift && current("leg");
    const choices = [["event", _("This test event")]];
    const shiftNumber = shift && (shift.number ?? shift.id);
    if (shift) choices.push(["shift", _("This shift (Shift %(shift)s)", { shift: shiftNumber })]);
    if (leg) choices.push(["leg", _("This leg (Shift %(shift)s · Leg %(leg)s)", { shift: shiftNumber, leg: leg.number ?? leg.id })]);
    const spec = { name: "scope", label: _("Report of"), type: "select", required: true, choices };
    const field = buildField(spec, choices[choices.length - 1][0]);
    const chosen = (form) => ({ event: {}, shift: { shift: shift?.id }, leg: { leg: leg?.id } })[form.elements.scope.value];
    return { field, chosen };
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
      const when = `${fmtTime(r.created)}${r.scope && r.kind !== "comparison" ? ` · ${r.scope}` : ""}`;
      if (r.download) {
        const a = document.createElement("a");
        a.href = r.download;
        a.textContent = _("Report of %(when)s (PDF)", { when });
        li.append(a, r.provisional ? ` — ${_("provisional: the test event was still open")}` : "");
      } else {
        // How long reports like it took, as the server read it from the finished ones.
        const expected = r.expected_seconds ? ` · ${_("reports like it took about %(seconds)s s; %(elapsed)s s so far", { seconds: fmtNumber(r.expected_seconds, 0), elapsed: fmtNumber(Math.max(0, (Date.now() - Date.parse(r.created)) / 1000), 0) })}` : "";
        li.textContent = `${_("Report of %(when)s: %(status)s", { when, status: JOB_STATUS[r.status] || r.status })}${r.progress !== null && r.progress !== undefined ? ` ${Math.round(r.progress * 100)} %` : ""}${expected}${r.error ? ` — ${r.error}` : r.message ? ` — ${r.message}` : ""}`;
      }
      ul.append(li);
    }
    const h = document.createElement("h3");
    h.textContent = list.length ? _("Reports of this test event") : _("No reports of this test event yet.");
    box.replaceChildren(h, ul);
    if (list.some((r) => r.status === "queued" || r.status === "running")) {
      this.timer = setTimeout(() => this.refresh(event).catch(showError), 1000);
    }
  },
};
