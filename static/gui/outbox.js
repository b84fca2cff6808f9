/* Writes kept while the server cannot be reached: quick reasons, new take-overs,
 * notes, segment edits and photos wait in this browser (IndexedDB, so a reload
 * keeps them), shown as "N waiting to send", and go to the server in the order
 * they were made once the live link is back.  Each carries the uid its row will
 * have (or, for a reason, the take-over the operator saw), so that a write sent
 * again after a lost answer is stored once: the server decides (common/retries.py).
 * A write the server refuses is dropped and the operator is told why.
 *
 * Every write answers within ANSWER_MS: one the server has not answered by then
 * is kept (its request goes on, and is awaited before the kept copy is sent).
 * Kept writes belong to the account that made them: another sign-in neither
 * sees nor sends them, and signing out asks before it deletes them. */
import { CONFIG, $ } from "./dom.js";
import { ApiError, api, plainMessage } from "./api.js";
import { notice, showError } from "./feedback.js";
import { Live } from "./live.js";
import { _, plural } from "./i18n.js";
import { confirmDialog } from "./dialogs.js";

const DB_NAME = "ftt-outbox";
const STORE = "writes";
// How long a write may wait for its answer before it is kept for later.
const WAIT_MS = 8000;
const WAIT_FILE_MS = 60000;
// How long a tap waits for the server before it is told "kept, will be sent".
const ANSWER_MS = 1000;
// Requests still under way for writes already kept, by their seq in the store.
const underWay = new Map();

/* A uid for a new row.  crypto.randomUUID exists only on https (and localhost);
 * field laptops may reach the server over plain http. */
export function newUid() {
  if (crypto.randomUUID) return crypto.randomUUID();
  const b = crypto.getRandomValues(new Uint8Array(16));
  b[6] = (b[6] & 0x0f) | 0x40;
  b[8] = (b[8] & 0x3f) | 0x80;
  const h = Array.from(b, (x) => x.toString(16).padStart(2, "0")).join("");
  return `${h.slice(0, 8)}-${h.slice(8, 12)}-${h.slice(12, 16)}-${h.slice(16, 20)}-${h.slice(20)}`;
}

let opened = null;
function database() {
  opened ||= new Promise((resolve, reject) => {
    const request = indexedDB.open(DB_NAME, 1);
    request.onupgradeneeded = () => request.result.createObjectStore(STORE, { keyPath: "seq", autoIncrement: true });
    request.onsuccess = () => resolve(request.result);
    request.onerror = () => reject(request.error);
  });
  return opened;
}

/* One request on the store, resolved once its transaction has committed. */
async function onStore(mode, call) {
  const db = await database();
  return new Promise((resolve, reject) => {
    const tx = db.transaction(STORE, mode);
    const request = call(tx.objectStore(STORE));
    tx.oncomplete = () => resolve(request.result);
    tx.onerror = () => reject(tx.error);
    tx.onabort = () => reject(tx.error);
  });
}

/* A failure that says nothing about the write: the link, not the server's rules. */
function unreachable(err) {
  if (err instanceof ApiError) return [502, 503, 504].includes(err.status);
  return err instanceof TypeError || ["AbortError", "TimeoutError"].includes(err && err.name);
}

function send(entry) {
  let body = entry.body;
  // A take-over kept while offline happened when it was tapped: the server is told
  // how long ago, by this browser's own clock (a tablet's wrong date cancels out).
  if (entry.timed && entry.made) body = { ...body, seconds_ago: Math.max(0, (Date.now() - Date.parse(entry.made)) / 1000) };
  if (entry.form) {
    body = new FormData();
    for (const [k, v] of Object.entries(entry.form.fields)) body.append(k, v);
    body.append(entry.form.fileField, entry.form.file, entry.form.fileName);
  }
  const root = entry.gui ? CONFIG.guiApiRoot : CONFIG.apiRoot;
  const signal = AbortSignal.timeout(entry.form ? WAIT_FILE_MS : WAIT_MS);
  return api(entry.method, entry.path, body, { root, signal, reason: entry.reason });
}

export const Outbox = {
  busy: false,
  /* Sends `entry` ({method, path, body or form, gui, what, kept, reason, timed}) now if the
   * server can be reached: {answer}.  Otherwise, or while earlier writes still
   * wait (they go first), keeps it: {kept: true}.  `kept` replaces `body` in
   * what is kept (a quick reason names the take-over seen).  Refusals throw. */
  async write(entry) {
    const waiting = await this.count();
    // A dead link is not tried: its request would only wait out WAIT_MS.
    if (!waiting && ["live", "connecting"].includes(Live.link)) {
      const sending = send(entry);
      const late = Symbol("late");
      const timer = new Promise((resolve) => setTimeout(resolve, ANSWER_MS, late));
      try {
        const answer = await Promise.race([sending, timer]);
        if (answer !== late) return { answer };
      } catch (err) {
        if (!unreachable(err)) throw err;
        return this.keep(entry);
      }
      // No answer yet on a slow or half-open link: kept now, the request goes on.
      return this.keep(entry, sending);
    }
    return this.keep(entry);
  },
  /* Keeps `entry`; `sending`: its request still under way, which flush awaits. */
  async keep(entry, sending = null) {
    const { kept, ...rest } = entry;
    if (kept) rest.body = kept;
    rest.made = new Date().toISOString();
    rest.account = CONFIG.account;
    const seq = await onStore("readwrite", (s) => s.add(rest));
    if (sending) {
      underWay.set(seq, sending.then(() => true, (err) => (unreachable(err) ? false : Promise.reject(err))));
      sending.finally(() => Live.link === "live" && this.flush()).catch(() => {});
    }
    await this.show();
    notice(_("Kept in this browser: %(what)s. It is sent when the server can be reached.", { what: entry.what }));
    if (Live.link === "live" && !sending) this.flush();
    return { kept: true };
  },
  /* This account's kept writes, oldest first. */
  async pending() {
    const all = await onStore("readonly", (s) => s.getAll());
    return all.filter((e) => e.account === CONFIG.account);
  },
  /* Forgets every kept write of this browser (signing out). */
  clear() {
    underWay.clear();
    return onStore("readwrite", (s) => s.clear());
  },
  async count() {
    return (await this.pending()).length;
  },
  /* The kept writes, oldest first, one at a time: a take-over before the reason given to it. */
  async flush() {
    if (this.busy) return;
    this.busy = true;
    const refused = [];
    let sent = 0;
    try {
      for (const entry of await this.pending()) {
        try {
          // The first request may still arrive: the kept copy is sent only if it did not.
          const arrived = await underWay.get(entry.seq);
          underWay.delete(entry.seq);
          if (!arrived) await send(entry);
          sent += 1;
        } catch (err) {
          // Still cut: this and the later ones wait for the next try, in order.
          if (unreachable(err)) return;
          refused.push(`${entry.what}: ${plainMessage(err)}`);
        }
        await onStore("readwrite", (s) => s.delete(entry.seq));
        await this.show();
      }
    } finally {
      this.busy = false;
      await this.show();
      if (sent) notice(plural(ngettext("%(count)s kept write sent.", "%(count)s kept writes sent.", sent), sent));
      if (refused.length) showError(new ApiError(_("Not sent, kept while offline: %(writes)s", { writes: refused.join(" · ") })));
    }
  },
  /* Reasons kept for take-overs, by take-over id: the list shows them until sent. */
  keptReasons: {},
  // Called when what is kept changes (main.js redraws the list).
  changed: () => {},
  async show() {
    const kept = await this.pending();
    const n = kept.length;
    this.keptReasons = Object.fromEntries(kept.filter((e) => e.gui && e.path.endsWith("/quick-reason/") && e.body.take_over).map((e) => [e.body.take_over, e.body.reason]));
    this.changed();
    const badge = $("#outbox");
    badge.hidden = n === 0;
    badge.textContent = plural(ngettext("%(count)s waiting to send", "%(count)s waiting to send", n), n);
    badge.dataset.count = n;
  },
};

/* Signing out leaves nothing of this account in the browser: kept writes (asked
 * first, they would be lost) and the service worker's copies of the cockpit,
 * so the next person neither sees this one's data offline nor sends their writes. */
export async function signOut(form) {
  const n = await Outbox.count().catch(() => 0);
  if (n) {
    const question = plural(ngettext("%(count)s change made here is not sent yet. Signing out deletes it.", "%(count)s changes made here are not sent yet. Signing out deletes them.", n), n);
    if (!(await confirmDialog(question, { yes: _("Delete and sign out"), no: _("Stay signed in") }))) return;
  }
  await Outbox.clear().catch(() => {});
  if (window.caches) {
    for (const name of await caches.keys()) if (name.startsWith("ftt-cockpit")) await caches.delete(name);
  }
  form.submit();
}

const signOutForm = $("#sign-out");
if (signOutForm) {
  signOutForm.addEventListener("submit", (e) => {
    e.preventDefault();
    signOut(signOutForm).catch(showError);
  });
}
