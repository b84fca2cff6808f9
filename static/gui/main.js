/* FTT operator GUI, the entry point (templates/gui/index.html loads it as a
 * module).  Every change goes through the REST API, which applies the rules;
 * the modules only show state and forward taps.  This one starts the page and
 * wires the change feed to the modules it concerns. */
import { CONFIG, $, $$ } from "./dom.js";
import { forgetBootstrap } from "./bootstrap.js";
import { showError } from "./feedback.js";
import { current, fromUrl, state } from "./state.js";
import { Live, onSelectedLeg } from "./live.js";
import { loadCatalogues, loadLevel } from "./levels.js";
import { appendPoses, applySegments, drawTakeOvers, loadSegments, refreshDistances, renderMode, renderSegments } from "./segments.js";
import { gpsMap, loadLocalMap, localMap } from "./mapview.js";
import { dialogSegment, loadImages, loadNotes } from "./segment-dialog.js";
import { Collector } from "./collector.js";
import { refreshSnapshots } from "./snapshots.js";
import { Fleet } from "./fleet.js";
import { Outbox } from "./outbox.js";
import { TestPlan } from "./testplan.js";
import "./parameters.js";
import "./reports.js";

/* What each kind of change-feed event changes on the page. */
Live.on("log", (e) => {
  Live.later("logs");
  // Closing a level closes the segments below it.
  if (e.test_event === state.selected.event) Live.later("segments");
});
Live.on("deleted", (e) => {
  const what = { note: "notes", image: "images", segment: "segments", mapimage: "map", recording: "recordings" }[e.payload.model];
  Live.later(what || "logs");
});
Live.on("segment", (e) => {
  if (onSelectedLeg(e) && !applySegments(e)) Live.later("segments");
});
// The open leg's test-case progress moves with its segments and positions.
for (const kind of ["segment", "poses", "log"]) {
  Live.on(kind, (e) => {
    if (onSelectedLeg(e) || kind === "log") TestPlan.later();
  });
}
Live.on("note", () => Live.later("notes"));
Live.on("image", () => Live.later("images"));
Live.on("recording", () => Live.later("recordings"));
Live.on("poses", appendPoses);
Live.on("local_poses", appendPoses);
Live.on("map", (e) => {
  if (e.shift === state.selected.shift) Live.later("map");
});
Live.on("command", (e) => Collector.commandAnswered(e));
Live.on("collector", () => Collector.refresh());
// The fleet view hears every logging robot's mode and positions (it subscribes with
// fleet: true) and applies them; a collector's or a log's change is read again.
for (const kind of ["segment", "poses"]) Live.on(kind, (e) => Fleet.apply(e));
for (const kind of ["collector", "log"]) {
  Live.on(kind, () => {
    if (Fleet.visible()) Live.later("fleet");
  });
}

/* The refreshes, in this order: the pickers may change the leg the rest draws. */
Live.onRefresh(["logs"], () => loadLevel("event"));
Live.onRefresh(["segments"], async () => {
  if (!state.selected.leg) return;
  await loadSegments();
  drawTakeOvers();
});
Live.onRefresh(["tracks", "distances"], async (what) => {
  if (state.selected.leg) await refreshDistances(what.has("tracks"));
});
Live.onRefresh(["map"], async () => {
  if (state.selected.leg) await loadLocalMap();
});
// A note being edited is not thrown away by somebody else's change.
Live.onRefresh(["notes"], async () => {
  if (dialogSegment) await loadNotes({ keepEditing: true });
});
Live.onRefresh(["images"], async () => {
  if (dialogSegment) await loadImages();
});
Live.onRefresh(["recordings"], refreshSnapshots);
Live.onRefresh(["fleet"], () => Fleet.refresh());

/* The service worker keeps the cockpit's files and last answers, so that a
 * reload on a dead link opens it (static/gui/sw.js); what this page loaded
 * before the worker ran is named to it. */
function keepCockpit() {
  const sw = navigator.serviceWorker;
  if (!sw) return; // plain http off localhost: no service worker, the outbox still works
  sw.register("/sw.js").catch(() => {});
  sw.ready.then((registration) => {
    const files = $$("script[src], link[rel=stylesheet], link[rel=modulepreload], link[rel=icon]").map((el) => el.src || el.href);
    registration.active.postMessage({ keep: [location.href, ...files] });
  });
}

async function boot() {
  const catalogues = loadCatalogues();
  if (!CONFIG.canOperate) $$(".op").forEach((b) => (b.disabled = true));
  Live.connect();
  // Nothing in the address: what the server says a bare address opens (this
  // browser's last cockpit, the one logging leg, or the fleet to pick from).
  const opening = !fromUrl.event && !fromUrl.view ? CONFIG.opening : null;
  if (opening && opening.view) state.view = opening.view;
  else if (opening) Object.assign(state.selected, opening);
  Live.onLink = (link) => {
    renderMode();
    // Writes kept while the link was dead go as soon as it is back.
    if (link === "live") Outbox.flush().catch(showError);
  };
  Outbox.changed = renderSegments;
  Outbox.show().catch(showError);
  keepCockpit();
  setInterval(() => {
    Live.watch();
    renderMode();
    gpsMap.tickRobot();
    localMap.tickRobot();
    Fleet.tick();
  }, 1000);
  if (state.view === "fleet") Fleet.show(true).catch(showError);
  try {
    await catalogues;
    await loadLevel("event");
  } catch (err) {
    showError(err);
  } finally {
    forgetBootstrap();
  }
  setInterval(() => {
    // Open segments' durations keep growing between events.
    if (state.segments.some((s) => s.is_open)) renderSegments();
    if (current("shift")) Collector.refresh();
    // Collectors that stop beating turn offline without a change-feed event.
    Fleet.refresh().catch(showError);
    // A flush cut short by the link (it may look live a moment longer) tries again.
    if (Live.link === "live") Outbox.flush().catch(showError);
  }, 5000);
}

if ($("#pick-event")) boot();
