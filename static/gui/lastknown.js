/* The last known truth, kept in this browser (localStorage) as the live link
 * last brought it: each shown leg's segment rows with their labels and open
 * take-over and the change feed's newest id (when the server last spoke is
 * live.js's `ftt.heard`).  A
 * reload on a dead or stalled link (the service worker answers with the page
 * as it was last loaded, maybe the fleet's) shows this, marked with its age,
 * instead of what the page held when it was last loaded. */
const KEY = "ftt.lastKnown";
const LEGS = 3; // the legs kept, the newest shown first
const EVERY_MS = 500; // written at most this often, the newest state always last

let timer = null;
let pending = null;

function read() {
  try {
    const kept = JSON.parse(localStorage.getItem(KEY) || "[]");
    return Array.isArray(kept) ? kept : [];
  } catch {
    return [];
  }
}

/* Keep `snapshot` ({leg, segments, labels, short_labels, open_take_over,
 * last_event}) soon, in the shape of the segment read's answer: many messages a second are written once. */
export function keepLeg(snapshot) {
  pending = snapshot;
  if (!timer) timer = setTimeout(write, EVERY_MS);
}

function write() {
  clearTimeout(timer);
  timer = null;
  const leg = pending;
  pending = null;
  if (!leg) return;
  try {
    const others = read().filter((k) => k.leg !== leg.leg);
    localStorage.setItem(KEY, JSON.stringify([leg, ...others].slice(0, LEGS)));
  } catch {
    // A full store keeps the copy before; the page goes on.
  }
}

// Leaving the page (a reload, another address) writes what is still waiting.
addEventListener("pagehide", write);

/* What this browser kept of `leg`, or null. */
export function keptLeg(leg) {
  return (pending && pending.leg === leg ? pending : null) || read().find((k) => k.leg === leg) || null;
}
