/* The cockpit's service worker (served as /sw.js, gui/views/pages.py): it keeps
 * the last answer of the cockpit page, its static files and its reads, so that
 * a reload on a dead link still opens the cockpit with what it showed last.
 *
 * Network first, always: the server's answer is the truth and replaces the kept
 * one.  Only when the server cannot be reached (an error, or no answer within
 * WAIT_MS on a half-open link) is the kept answer used, and for DEAD_MS after
 * such a miss the kept answers come at once instead of waiting again.  Writes
 * are never touched: the page keeps those itself (outbox.js). */
const CACHE = "ftt-cockpit-v1";
const WAIT_MS = 4000;
const DEAD_MS = 10000;
let deadUntil = 0;

self.addEventListener("install", () => self.skipWaiting());
self.addEventListener("activate", (event) => event.waitUntil(self.clients.claim()));

// Reads that say what is true now (robot online, fleet): a kept copy would lie.
const LIVE_ONLY = ["/gui/api/collectors/", "/gui/api/fleet/"];

/* What is worth keeping: the cockpit page and what it reads; not media, tiles,
 * the admin or a map's detail for one view (its bbox changes with every pan). */
function kept(request) {
  if (request.method !== "GET") return false;
  const url = new URL(request.url);
  if (url.origin !== self.location.origin || url.searchParams.has("bbox")) return false;
  if (LIVE_ONLY.some((p) => url.pathname.startsWith(p))) return false;
  if (request.mode === "navigate") return url.pathname === "/";
  // The catalogue of the page's language (/jsi18n/) too: the scripts call its gettext.
  return ["/static/", "/api/", "/gui/api/", "/jsi18n/"].some((p) => url.pathname.startsWith(p));
}

/* The server's answer, handed on at once; `stored` gets the promise of keeping it. */
async function fromNetwork(request, stored = () => {}) {
  const controller = new AbortController();
  const timer = setTimeout(() => controller.abort(), WAIT_MS);
  try {
    const response = await fetch(request, { signal: controller.signal });
    // A redirect to the sign-in page is no cockpit to keep, and says the kept
    // copies belong to a session that has ended: they are dropped.
    if (response.redirected && new URL(response.url).pathname.startsWith("/login")) stored(caches.delete(CACHE));
    else if (response.ok && !response.redirected) {
      const copy = response.clone();
      stored(caches.open(CACHE).then((cache) => cache.put(request, copy)));
    }
    return response;
  } finally {
    clearTimeout(timer);
  }
}

/* The page names what it loaded before this worker ran (the page itself, its
 * scripts and styles): kept now, so that the first reload on a dead link works. */
self.addEventListener("message", (event) => {
  const urls = (event.data && event.data.keep) || [];
  const same = urls.filter((u) => new URL(u).origin === self.location.origin);
  const keeping = same.map(async (u) => {
    let put = null;
    await fromNetwork(new Request(u), (p) => (put = p)).catch(() => null);
    await put;
  });
  event.waitUntil(Promise.all(keeping));
});

async function answer(request, stored) {
  const cache = await caches.open(CACHE);
  if (Date.now() < deadUntil) {
    const hit = await keptAnswer(cache, request);
    if (hit) return hit;
  }
  try {
    const response = await fromNetwork(request, stored);
    deadUntil = 0;
    return response;
  } catch (err) {
    deadUntil = Date.now() + DEAD_MS;
    const hit = await keptAnswer(cache, request);
    if (hit) return hit;
    throw err;
  }
}

/* The kept answer; for the cockpit page, kept under any selection: the page
 * takes the selection from its address and reads the rest (kept too). */
async function keptAnswer(cache, request) {
  const hit = await cache.match(request, { ignoreVary: true });
  if (hit || request.mode !== "navigate") return hit;
  return cache.match(request, { ignoreSearch: true, ignoreVary: true });
}

/* A sign-in starts a session, perhaps another account's: the copies kept for the
 * one before are dropped, and the page after it is asked of the server even just
 * after a miss (a kept cockpit names the account before, and would send the
 * writes that account kept). */
function signingIn(request) {
  return request.method === "POST" && new URL(request.url).pathname.startsWith("/login");
}

self.addEventListener("fetch", (event) => {
  if (signingIn(event.request)) {
    deadUntil = 0;
    event.waitUntil(caches.delete(CACHE));
  } else if (kept(event.request)) event.respondWith(answer(event.request, (p) => event.waitUntil(p)));
});
