/* The comparison page (templates/gui/compare.html loads it as a module): pick test
 * events, see MDBI, MTBI and interventions per km and per hour with their bounds side
 * by side, and get the comparison PDF (with the routes compared below, if any: routes.js).
 * Every figure and its wording comes from the server (/api/reports/compare/ formats them
 * as the PDF does); this script only shows them and asks for the PDF job. */

import { CONFIG, $, element } from "./dom.js";
import { api, list, plainMessage } from "./api.js";
import { LANGUAGE, _, plural } from "./i18n.js";
import { shownRoutes } from "./routes.js";

const POLL_MS = 1000;

/* The choice lives in the address, so a reload or a shared link shows the same comparison. */
function readAddress() {
  const q = new URLSearchParams(location.search);
  return {
    events: q.getAll("event").filter((v) => /^\d+$/.test(v)).map(Number),
    mode: q.get("mode") === "local" ? "local" : "gps",
    job: /^\d+$/.test(q.get("job") || "") ? Number(q.get("job")) : null,
  };
}

function writeAddress() {
  const q = new URLSearchParams();
  for (const id of state.chosen) q.append("event", id);
  if (state.mode !== "gps") q.set("mode", state.mode);
  if (state.job) q.set("job", state.job);
  history.replaceState(null, "", `${location.pathname}?${q}`);
}

const start = readAddress();
const state = { events: [], chosen: new Set(start.events), mode: start.mode, job: start.job, data: null };

function say(text, isError = false) {
  const line = $("#compare-status");
  line.replaceChildren(document.createTextNode(text));
  line.classList.toggle("error", isError);
}

function pairs(rows) {
  return element("dl", { className: "pairs" }, rows.flatMap(([k, v]) => [element("dt", { textContent: k }), element("dd", { textContent: v })]));
}

function chosenInOrder() {
  return state.events.filter((e) => state.chosen.has(e.id)).map((e) => e.id);
}

function updateButtons() {
  const enough = state.chosen.size >= 2;
  $("#compare-run").disabled = !enough;
  $("#compare-pdf").disabled = !enough || !CONFIG.canOperate;
  $("#compare-pdf").title = CONFIG.canOperate ? "" : _("Making a PDF needs the operator role.");
}

function showEvents() {
  const list = $("#event-list");
  const rows = state.events.map((e) => {
    const box = element("input", { type: "checkbox", value: e.id, checked: state.chosen.has(e.id) });
    box.addEventListener("change", () => {
      if (box.checked) state.chosen.add(e.id);
      else state.chosen.delete(e.id);
      writeAddress();
      updateButtons();
    });
    const when = e.start ? new Date(e.start).toLocaleDateString(LANGUAGE) : "";
    const text = `#${e.id} ${e.location || _("no location")} · ${when}${e.version ? ` · ${e.version}` : ""}`;
    return element("label", {}, [box, element("span", { textContent: text })]);
  });
  list.replaceChildren(...rows);
  if (!rows.length) list.append(element("p", { className: "muted", textContent: _("No test events yet.") }));
  updateButtons();
}

const FIGURE_ROWS = [
  [_("Interventions"), "interventions"],
  [_("Autonomous distance"), "auto_distance"],
  [_("Autonomous time"), "auto_time"],
  ["MDBI", "mdbi"],
  // xgettext:no-javascript-format
  [_("MDBI 90 % bounds"), "mdbi_bounds"],
  ["MTBI", "mtbi"],
  // xgettext:no-javascript-format
  [_("MTBI 90 % bounds"), "mtbi_bounds"],
  [_("Interventions per km"), "per_km"],
  [_("Interventions per hour"), "per_hour"],
];

function figureCards(target, groups, title) {
  $(target).replaceChildren(
    ...groups.map((g) => element("article", { className: "card" }, [
      element("h3", { textContent: title(g) }),
      pairs(FIGURE_ROWS.map(([label, key]) => [label, g.shown[key]])),
    ])),
  );
}

function segmentLink(member) {
  const q = new URLSearchParams({ event: member.test_event, shift: member.shift, leg: member.leg, segment: member.segment });
  const name = state.events.find((e) => e.id === member.test_event);
  const text = `#${member.test_event}${name && name.location ? ` ${name.location}` : ""}: ${member.label}`;
  return element("a", { href: `/?${q}`, textContent: text });
}

function showComparison(data) {
  figureCards("#by-event", data.test_events, (e) => `#${e.id} ${e.name}`);
  figureCards("#by-version", data.versions, (v) => v.version);
  figureCards("#by-vehicle", data.vehicles, (v) => v.name);
  const fit = data.growth.fit_rows;
  $("#growth-fit").replaceChildren(...(fit.length ? pairs(fit).childNodes : [element("dd", { textContent: _("Fewer than two interventions: no growth fit.") })]));
  $("#hotspot-note").textContent = _("Take-overs at most %(radius)s m apart form one hotspot; numbers as on the PDF's map.", { radius: data.hotspot_radius });
  const reasonName = (key) => (data.reasons[key] ? data.reasons[key].name : key);
  const spots = data.hotspots.map((spot) => {
    const reasons = Object.entries(spot.reasons).map(([key, n]) => {
      const colour = data.reasons[key] ? `rgb(${data.reasons[key].color})` : "grey";
      return element("span", {}, [element("span", { className: "swatch", style: `background:${colour}` }), `${reasonName(key)} (${n}) `]);
    });
    return element("li", {}, [
      element("strong", { textContent: `${plural(ngettext("%(count)s take-over", "%(count)s take-overs", spot.count), spot.count)}: ` }),
      ...reasons,
      element("div", {}, spot.members.map(segmentLink)),
    ]);
  });
  $("#hotspots").replaceChildren(...spots);
  if (!spots.length) $("#hotspots").append(element("li", { className: "muted", textContent: _("No take-over with a position.") }));
  $("#compare-results").hidden = false;
}

async function runComparison() {
  const ids = chosenInOrder();
  if (ids.length < 2) return;
  say(_("Comparing…"));
  const q = new URLSearchParams(ids.map((id) => ["test_event", id]));
  q.set("mode", state.mode);
  try {
    state.data = await api("GET", `reports/compare/?${q}`);
    showComparison(state.data);
    say(_("Compared %(count)s test events.", { count: ids.length }));
  } catch (err) {
    say(plainMessage(err), true);
  }
}

function showJob(job) {
  const line = $("#compare-status");
  if (job.status === "done") {
    const link = element("a", { className: "download", href: job.download, textContent: _("Download the comparison PDF") });
    line.classList.remove("error");
    line.replaceChildren(link);
    return true;
  }
  if (job.status === "failed") {
    say(_("The PDF failed: %(error)s", { error: job.error }), true);
    return true;
  }
  say(_("Making the PDF: %(status)s, %(percent)s", { status: job.status, percent: `${Math.round(job.progress * 100)} %` }));
  return false;
}

async function followJob() {
  while (state.job) {
    let job;
    try {
      job = await api("GET", `reports/${state.job}/`);
    } catch (err) {
      say(plainMessage(err), true);
      return;
    }
    if (showJob(job)) return;
    await new Promise((resolve) => setTimeout(resolve, POLL_MS));
  }
}

async function makePdf() {
  $("#compare-pdf").disabled = true;
  const routes = shownRoutes();
  say(routes ? _("Asking for the PDF, with the routes compared below…") : _("Asking for the PDF…"));
  const options = { local: state.mode === "local", ...(routes ? { routes } : {}) };
  try {
    const job = await api("POST", "reports/", { compare: chosenInOrder(), options });
    state.job = job.id;
    writeAddress();
    await followJob();
  } catch (err) {
    say(plainMessage(err), true);
  } finally {
    updateButtons();
  }
}

async function main() {
  $("#compare-mode").value = state.mode;
  $("#compare-mode").addEventListener("change", (event) => {
    state.mode = event.target.value;
    writeAddress();
  });
  $("#compare-run").addEventListener("click", runComparison);
  $("#compare-pdf").addEventListener("click", makePdf);
  try {
    state.events = (await list("test-events/")).sort((a, b) => (a.start < b.start ? 1 : -1));
  } catch (err) {
    say(plainMessage(err), true);
    return;
  }
  showEvents();
  if (state.chosen.size >= 2) await runComparison();
  if (state.job) await followJob();
}

if ($("#event-list")) main();
