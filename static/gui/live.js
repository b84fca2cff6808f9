/* Live updates: the websocket ws/live/ carries the server's change feed for
 * the selected event, shift and leg (see docs/gui.md).  This module keeps the
 * connection and batches refreshes; what each kind of event changes on the
 * page is registered with on() and onRefresh(). */
import { CONFIG, $ } from "./dom.js";
import { showError } from "./feedback.js";
import { state } from "./state.js";

export const Live = {
  socket: null,
  retry: 500,
  pending: new Set(),
  seen: new Set(), // ids of the events applied
  timer: null,
  connect() {
    const scheme = location.protocol === "https:" ? "wss:" : "ws:";
    const socket = new WebSocket(`${scheme}//${location.host}${CONFIG.wsPath}`);
    this.socket = socket;
    socket.onopen = () => {
      this.retry = 500;
      this.setStatus("live", "ok");
      this.subscribe();
    };
    socket.onmessage = (e) => this.receive(JSON.parse(e.data));
    socket.onclose = (e) => {
      if (this.socket !== socket) return;
      if (e.code === 4403) {
        this.setStatus("no live updates (no role)", "bad");
        return;
      }
      this.setStatus("reconnecting…", "bad");
      setTimeout(() => this.connect(), this.retry);
      this.retry = Math.min(this.retry * 2, 5000);
    };
  },
  setStatus(text, kind) {
    const badge = $("#live-status");
    badge.textContent = text;
    badge.className = `badge ${kind || ""}`;
    badge.dataset.state = kind || "";
  },
  subscribe() {
    if (!this.socket || this.socket.readyState !== WebSocket.OPEN) return;
    this.socket.send(JSON.stringify({
      type: "subscribe",
      test_event: state.selected.event,
      shift: state.selected.shift,
      leg: state.selected.leg,
      fleet: state.view === "fleet",
      last_id: state.lastEventId,
    }));
  },
  receive(message) {
    if (message.type === "subscribed") {
      if (state.lastEventId === null || message.last_id > state.lastEventId) state.lastEventId = message.last_id;
      return;
    }
    if (message.type === "reset") {
      state.lastEventId = message.last_id;
      state.shownLeg = undefined;
      this.later("logs");
      return;
    }
    if (message.type !== "events") return;
    for (const e of message.events) {
      // Each subscription catches up from lastEventId: two in flight bring the same events.
      if (this.seen.has(e.id)) continue;
      this.seen.add(e.id);
      if (this.seen.size > 10000) this.seen.delete(this.seen.values().next().value);
      if (e.id > (state.lastEventId || 0)) state.lastEventId = e.id;
      this.apply(e);
    }
  },
  /* Each module says what an event of a kind means for it (main.js wires them). */
  handlers: new Map(),
  on(kind, handler) {
    if (!this.handlers.has(kind)) this.handlers.set(kind, []);
    this.handlers.get(kind).push(handler);
  },
  apply(e) {
    for (const handler of this.handlers.get(e.kind) || []) handler(e);
  },
  /* Bursts of events become one refresh per kind. */
  later(what) {
    this.pending.add(what);
    if (this.timer) return;
    this.timer = setTimeout(() => this.flush(), 40);
  },
  /* run(what) once per burst in which one of `keys` was asked for; refreshers
   * run one after another in the order they were added, so a refresh can rely
   * on the ones before it (the pickers before the segments of the leg). */
  refreshers: [],
  onRefresh(keys, run) {
    this.refreshers.push({ keys, run });
  },
  async flush() {
    const what = this.pending;
    this.pending = new Set();
    this.timer = null;
    try {
      for (const { keys, run } of this.refreshers) if (keys.some((k) => what.has(k))) await run(what);
    } catch (err) {
      showError(err);
    }
  },
};

/* Whether a change-feed event belongs to the leg on screen. */
export const onSelectedLeg = (e) => e.leg !== null && e.leg === state.selected.leg;
