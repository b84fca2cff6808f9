/* Live updates: the websocket ws/live/ carries the server's change feed for
 * the selected event, shift and leg (see docs/gui.md).  This module keeps the
 * connection and batches refreshes; what each kind of event changes on the
 * page is registered with on() and onRefresh(). */
import { CONFIG, $ } from "./dom.js";
import { _ } from "./i18n.js";
import { showError } from "./feedback.js";
import { state } from "./state.js";

export const Live = {
  socket: null,
  retry: 500,
  // When the server last spoke, and how long a silence means a dead link (its heartbeat says).
  heard: Number(localStorage.getItem("ftt.heard")) || Date.now(),
  kept: 0, // when `heard` was last written to localStorage
  staleAfter: 3,
  link: "connecting", // "live", "stale" (silent though open) or "down" (closed, reconnecting)
  pending: new Set(),
  seen: new Set(), // ids of the events applied
  timer: null,
  connect() {
    const scheme = location.protocol === "https:" ? "wss:" : "ws:";
    const socket = new WebSocket(`${scheme}//${location.host}${CONFIG.wsPath}`);
    this.socket = socket;
    this.opened = Date.now();
    // Open is not yet live: the link is live once the server answers the
    // subscription, after the events missed meanwhile (receive).
    socket.onopen = () => {
      this.retry = 500;
      this.opened = Date.now();
      this.subscribe();
    };
    socket.onmessage = (e) => {
      // A socket given up as dead says nothing about the link now.
      if (this.socket !== socket) return;
      // Kept (once a second), so that a reload on a dead link still says how long ago.
      this.heard = Date.now();
      if (this.heard - this.kept > 1000) {
        this.kept = this.heard;
        localStorage.setItem("ftt.heard", String(this.heard));
      }
      this.receive(JSON.parse(e.data));
    };
    socket.onclose = (e) => {
      if (this.socket !== socket) return;
      if (e.code === 4403) {
        this.setStatus(_("no live updates (no role)"), "bad");
        return;
      }
      this.setLink("down");
      setTimeout(() => this.connect(), this.retry);
      this.retry = Math.min(this.retry * 2, 5000);
    };
  },
  /* Called every second: an open socket that stays silent past the heartbeat is a
   * dead link (a half-open Wi-Fi link never closes); it is dropped for a new one,
   * which catches up from the change feed once it opens. */
  watch() {
    const socket = this.socket;
    if (!socket) return;
    const silent = (Date.now() - Math.max(this.heard, this.opened)) / 1000;
    if (socket.readyState === WebSocket.OPEN && silent > this.staleAfter) {
      this.setLink("stale");
      this.socket = null;
      socket.close();
      this.connect();
    } else if (socket.readyState === WebSocket.CONNECTING && (Date.now() - this.opened) / 1000 > 2 * this.staleAfter) {
      this.socket = null;
      socket.close();
      this.connect();
    }
  },
  /* Seconds since the server last spoke until the link is proven live; null once it is. */
  lost() {
    return this.link === "live" ? null : Math.max(0, Math.round((Date.now() - this.heard) / 1000));
  },
  setLink(link) {
    this.link = link;
    const words = { live: [_("live"), "ok"], stale: [_("stale"), "stale"], down: [_("reconnecting…"), "bad"] };
    this.setStatus(...words[link]);
    this.onLink(link);
    if (link === "live") for (const run of this.waiting.splice(0)) run();
  },
  /* run() once, the next time the link is live (what a dead link kept the page from reading). */
  waiting: [],
  whenLive(run) {
    this.waiting.push(run);
  },
  onLink() {}, // main.js redraws the mode banner

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
      // The words events carry (segment labels) come in the page's language.
      language: document.documentElement.lang,
    }));
  },
  receive(message) {
    if (message.type === "heartbeat") {
      this.staleAfter = message.stale_after;
      return;
    }
    if (message.type === "subscribed") {
      if (state.lastEventId === null || message.last_id > state.lastEventId) state.lastEventId = message.last_id;
      // The server has answered, the missed events came before: what the page shows is live now.
      if (this.link !== "live") this.setLink("live");
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
      // On a dead link a refresh cannot succeed; the badge and banner say so, and
      // the page catches up once the link is back.
      if (this.link === "live" || !(err instanceof TypeError)) showError(err);
    }
  },
};

/* Whether a change-feed event belongs to the leg on screen. */
export const onSelectedLeg = (e) => e.leg !== null && e.leg === state.selected.leg;
