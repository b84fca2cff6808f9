/* The robot panel: the shift's vehicle's collector (ftt_collect), its inputs,
 * Start/Stop logging and Snapshot now; commands go to the robot through /gui/api/. */
import { CONFIG, $ } from "./dom.js";
import { ApiError, NETWORK_MESSAGE, api, plainMessage } from "./api.js";
import { clearError, notice, showError } from "./feedback.js";
import { current, state, vehicleName } from "./state.js";
import { _ } from "./i18n.js";
import { fmtNumber } from "./format.js";

// How long the robot panel waits for the server before it says it cannot reach it.
const STATUS_MS = 5000;

export const Collector = {
  status: null,
  async refresh() {
    const box = $("#collector-status");
    const button = $("#logging-toggle");
    const shift = current("shift");
    $("#collector").hidden = !shift;
    if (!shift) {
      this.vehicle = null;
      box.textContent = _("Select a shift to see its robot.");
      button.disabled = true;
      return;
    }
    if (this.vehicle !== shift.vehicle) {
      this.vehicle = shift.vehicle;
      box.textContent = _("Asking for the robot's status…");
    }
    try {
      // A half-open link would keep the last answer on screen as if it were now.
      this.status = await api("GET", `collectors/?vehicle=${shift.vehicle}&leg=${state.selected.leg || ""}`, undefined, { root: CONFIG.guiApiRoot, signal: AbortSignal.timeout(STATUS_MS) });
    } catch (err) {
      this.status = null;
      if (err.status === 404) box.textContent = _("Collector status is not available on this server.");
      else box.textContent = err.name === "TimeoutError" ? NETWORK_MESSAGE : plainMessage(err);
      // Without an answer there is nothing current to show of the robot.
      $("#collector-inputs").replaceChildren();
      $("#collector-warning").hidden = true;
      $("#logging-why").textContent = "";
      $("#snapshot-why").textContent = "";
      button.disabled = true;
      $("#snapshot-now").disabled = true;
      return;
    }
    this.render();
  },
  render() {
    const s = this.status;
    const button = $("#logging-toggle");
    const inputs = $("#collector-inputs");
    if (!s || !s.collector) {
      $("#collector-warning").hidden = true;
      $("#collector-status").textContent = _("No collector has reported for %(vehicle)s.", { vehicle: vehicleName(current("shift").vehicle) });
      inputs.replaceChildren();
      button.disabled = true;
      button.textContent = _("Start logging");
      $("#logging-why").textContent = "";
      $("#snapshot-now").disabled = true;
      $("#snapshot-why").textContent = "";
      return;
    }
    const c = s.collector;
    // The server says when the robot logs into an ended or missing leg (control.py).
    const warning = $("#collector-warning");
    warning.textContent = s.stores_nothing || "";
    warning.hidden = !s.stores_nothing;
    const doing = !c.logging ? _("not logging") : c.leg === state.selected.leg ? _("logging into this leg") : c.leg ? _("logging into another leg") : _("logging into no leg");
    const queue = c.pending ? ` · ${_("%(count)s records not yet stored", { count: fmtNumber(c.pending) })}` : "";
    // Set by the collector's watchdog, e.g. "robot publishes, collector hears nothing (…)".
    const hearing = c.online && c.hearing ? ` · ${c.hearing}` : "";
    // Set by the collector's disk guard, e.g. "robot disk full since 14:03, 2 snapshots dropped, …";
    // shown offline too, as the robot's last word (like the records not yet stored).
    const disk = c.disk ? ` · ${c.disk}` : "";
    $("#collector-status").textContent = _("%(vehicle)s (collector %(name)s): %(online)s, %(doing)s", { vehicle: vehicleName(current("shift").vehicle), name: c.name, online: c.online ? _("online") : _("offline"), doing }) + queue + hearing + disk;
    inputs.replaceChildren(...Object.entries(c.inputs || {}).map(([name, info]) => {
      const li = document.createElement("li");
      const age = info && typeof info.age === "number" ? _("%(age)s s ago", { age: fmtNumber(info.age, 1) }) : _("no data yet");
      // Counted by the collector (losses.py): sent but never handled, and not sent at the publisher's rate.
      const dropped = info && info.dropped ? " · " + _("%(count)s dropped", { count: info.dropped }) : "";
      const gaps = info && info.publisher_gaps ? " · " + _("publisher gaps: about %(count)s", { count: info.publisher_gaps }) : "";
      // Said by the collector when a publisher's QoS does not match its subscription.
      const qos = info && info.qos ? ` · ${info.qos}` : "";
      li.textContent = `${name}: ${age}${dropped}${gaps}${qos}`;
      return li;
    }));
    button.textContent = c.logging ? _("Stop logging") : _("Start logging");
    button.disabled = !CONFIG.canOperate || !s.can_toggle;
    $("#logging-why").textContent = s.reason || "";
    $("#snapshot-now").disabled = !CONFIG.canOperate || !s.can_snapshot;
    $("#snapshot-why").textContent = _("Snapshot: %(why)s", { why: s.snapshot_reason });
    $("#open-parameters").hidden = !CONFIG.canOperate || !c.online;
  },
  /* The robot's answer to a command, from the change feed. */
  commandAnswered(e) {
    const c = this.status && this.status.collector;
    if (c && e.collector === c.id) {
      if (e.payload.success === false) showError(new ApiError(_("The robot refused: %(message)s", { message: e.payload.message })));
      else if (e.payload.message) notice(_("Robot: %(message)s", { message: e.payload.message }));
    }
    this.refresh();
  },
  async command(kind, args = {}) {
    const c = this.status && this.status.collector;
    if (!c) throw new ApiError(_("No collector is connected for this vehicle."));
    const result = await api("POST", `collectors/${c.id}/commands/`, { kind, arguments: args, leg: state.selected.leg }, { root: CONFIG.guiApiRoot });
    await this.refresh();
    return result;
  },
};

$("#logging-toggle").addEventListener("click", async () => {
  clearError();
  try {
    const c = Collector.status && Collector.status.collector;
    await Collector.command(c && c.logging ? "stop_logging" : "start_logging");
  } catch (err) {
    showError(err);
  }
});

// The robot's answer (the snapshot's name, or why not) replaces this toast;
// it may come before the request's own reply does.
$("#snapshot-now").addEventListener("click", async () => {
  clearError();
  notice(_("Asking the robot for a snapshot…"));
  try {
    await Collector.command("snapshot");
  } catch (err) {
    showError(err);
  }
});
