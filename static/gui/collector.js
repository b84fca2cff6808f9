/* The robot panel: the shift's vehicle's collector (ftt_collect), its inputs,
 * Start/Stop logging and Snapshot now; commands go to the robot through /gui/api/. */
import { CONFIG, $ } from "./dom.js";
import { ApiError, api, plainMessage } from "./api.js";
import { clearError, notice, showError } from "./feedback.js";
import { current, state, vehicleName } from "./state.js";

export const Collector = {
  status: null,
  async refresh() {
    const box = $("#collector-status");
    const button = $("#logging-toggle");
    const shift = current("shift");
    $("#collector").hidden = !shift;
    if (!shift) {
      this.vehicle = null;
      box.textContent = "Select a shift to see its robot.";
      button.disabled = true;
      return;
    }
    if (this.vehicle !== shift.vehicle) {
      this.vehicle = shift.vehicle;
      box.textContent = "Asking for the robot's status…";
    }
    try {
      this.status = await api("GET", `collectors/?vehicle=${shift.vehicle}&leg=${state.selected.leg || ""}`, undefined, { root: CONFIG.guiApiRoot });
    } catch (err) {
      this.status = null;
      box.textContent = err.status === 404 ? "Collector status is not available on this server." : plainMessage(err);
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
      $("#collector-status").textContent = `No collector has reported for ${vehicleName(current("shift").vehicle)}.`;
      inputs.replaceChildren();
      button.disabled = true;
      button.textContent = "Start logging";
      $("#logging-why").textContent = "";
      $("#snapshot-now").disabled = true;
      $("#snapshot-why").textContent = "";
      return;
    }
    const c = s.collector;
    const into = c.leg === state.selected.leg ? "this leg" : c.leg ? "another leg" : "no leg";
    const doing = c.logging ? `logging into ${into}` : "not logging";
    const queue = c.pending ? ` · ${c.pending} records not yet stored` : "";
    // Set by the collector's watchdog, e.g. "robot publishes, collector hears nothing (…)".
    const hearing = c.online && c.hearing ? ` · ${c.hearing}` : "";
    // Set by the collector's disk guard, e.g. "robot disk full: positions thinned since 14:03, …";
    // shown offline too, as the robot's last word (like the records not yet stored).
    const disk = c.disk ? ` · ${c.disk}` : "";
    $("#collector-status").textContent = `${vehicleName(current("shift").vehicle)} (collector ${c.name}): ${c.online ? "online" : "offline"}, ${doing}${queue}${hearing}${disk}`;
    inputs.replaceChildren(...Object.entries(c.inputs || {}).map(([name, info]) => {
      const li = document.createElement("li");
      const age = info && typeof info.age === "number" ? `${info.age.toFixed(1)} s ago` : "no data yet";
      // Estimated by the collector from gaps in the robot's stamps (losses.py).
      const missed = info && info.missed ? ` · about ${info.missed} missed` : "";
      li.textContent = `${name}: ${age}${missed}`;
      return li;
    }));
    button.textContent = c.logging ? "Stop logging" : "Start logging";
    button.disabled = !CONFIG.canOperate || !s.can_toggle;
    $("#logging-why").textContent = s.reason || "";
    $("#snapshot-now").disabled = !CONFIG.canOperate || !s.can_snapshot;
    $("#snapshot-why").textContent = `Snapshot: ${s.snapshot_reason}`;
    $("#open-parameters").hidden = !CONFIG.canOperate || !c.online;
  },
  /* The robot's answer to a command, from the change feed. */
  commandAnswered(e) {
    const c = this.status && this.status.collector;
    if (c && e.collector === c.id) {
      if (e.payload.success === false) showError(new ApiError(`The robot refused: ${e.payload.message}`));
      else if (e.payload.message) notice(`Robot: ${e.payload.message}`);
    }
    this.refresh();
  },
  async command(kind, args = {}) {
    const c = this.status && this.status.collector;
    if (!c) throw new ApiError("No collector is connected for this vehicle.");
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
  notice("Asking the robot for a snapshot…");
  try {
    await Collector.command("snapshot");
  } catch (err) {
    showError(err);
  }
});
