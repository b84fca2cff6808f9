/* How times, durations, distances and numbers are written on the page. */
import { byId, state } from "./state.js";
import { LANGUAGE } from "./i18n.js";

/* Dates and numbers follow the page's language (LANGUAGE), not the browser's:
   a German page writes 26.11.2026 and 1,25 km wherever it is opened.
   Times are shown in the selected test event's time zone, as the model says. */
function zoneOptions() {
  const event = byId(state.rows.event, state.selected.event);
  return event && event.time_zone ? { timeZone: event.time_zone, timeZoneName: "short" } : {};
}
export function fmtTime(iso, options = {}) {
  if (!iso) return "—";
  try {
    return new Date(iso).toLocaleString(LANGUAGE, { ...zoneOptions(), ...options });
  } catch {
    return new Date(iso).toLocaleString(LANGUAGE, options);
  }
}
/* Time of day only: in the segment list the date is the leg's and would push
   duration and distance out of sight on a laptop; the full time is the title. */
const CLOCK = { hour: "2-digit", minute: "2-digit", second: "2-digit", hourCycle: "h23", timeZoneName: undefined };
export const fmtClock = (iso) => fmtTime(iso, CLOCK);
export const fmtDay = (iso) => (iso ? new Date(iso).toLocaleDateString(LANGUAGE) : "");

export function fmtDuration(start, end) {
  const seconds = Math.max(0, ((end ? new Date(end) : new Date()) - new Date(start)) / 1000);
  const h = Math.floor(seconds / 3600), m = Math.floor((seconds % 3600) / 60), s = Math.floor(seconds % 60);
  return h ? `${h} h ${m} min` : m ? `${m} min ${s} s` : `${s} s`;
}

export function fmtDistance(metres) {
  if (metres === null || metres === undefined) return "—";
  return metres >= 1000 ? `${fmtNumber(metres / 1000, 2)} km` : `${fmtNumber(metres, 1)} m`;
}

/* A number in the page's language; with `digits`, exactly that many decimals. */
export function fmtNumber(value, digits) {
  const fixed = digits === undefined ? {} : { minimumFractionDigits: digits, maximumFractionDigits: digits };
  return new Intl.NumberFormat(LANGUAGE, fixed).format(value);
}

/* ROS floats are 32-bit: 0.10000000149011612 is shown as 0.1. */
export const roundFloat = (v) => (typeof v === "number" ? Number(v.toPrecision(7)) : v);
