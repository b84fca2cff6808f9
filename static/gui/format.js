/* How times, durations, distances and numbers are written on the page. */
import { byId, state } from "./state.js";
import { LANGUAGE } from "./i18n.js";

/* Times are shown in the selected test event's time zone, as the model says. */
function zoneOptions() {
  const event = byId(state.rows.event, state.selected.event);
  return event && event.time_zone ? { timeZone: event.time_zone, timeZoneName: "short" } : {};
}
/* One way of writing a date per language, 24-hour clock, whatever the browser's
   locale: the page's language (LANGUAGE) decides (German 26.11.2026, else 2026-11-26). */
const DAY_ORDER = { de: (p) => `${p.day}.${p.month}.${p.year}` };
const isoDay = (p) => `${p.year}-${p.month}-${p.day}`;
/* Building an Intl formatter costs far more than using one, and a long leg's
   list writes hundreds of times per update: each is built once per set of options. */
const formats = new Map();
const MAKE = {
  date: (options) => new Intl.DateTimeFormat("en-GB", options),
  number: (options) => new Intl.NumberFormat(LANGUAGE, options),
};
function formatter(kind, options) {
  const key = kind + JSON.stringify(options);
  let format = formats.get(key);
  if (!format) formats.set(key, (format = MAKE[kind](options)));
  return format;
}
function parts(iso, options) {
  const format = formatter("date", {
    year: "numeric", month: "2-digit", day: "2-digit",
    hour: "2-digit", minute: "2-digit", second: "2-digit", hourCycle: "h23", ...options,
  });
  const out = {};
  for (const part of format.formatToParts(new Date(iso))) out[part.type] = part.value;
  return out;
}
function zoned(iso, options) {
  try {
    return parts(iso, { ...zoneOptions(), ...options });
  } catch {
    return parts(iso, options);
  }
}
const writeDay = (p) => (DAY_ORDER[LANGUAGE.slice(0, 2)] || isoDay)(p);
const writeClock = (p) => `${p.hour}:${p.minute}:${p.second}`;
const writeZone = (p) => (p.timeZoneName ? ` ${p.timeZoneName}` : "");

/* A segment's times are written again at each update of the list: each text is
   kept per zone and instant (a bounded store, emptied when full). */
const written = new Map();
function remembered(kind, iso, write) {
  const key = `${kind}|${zoneOptions().timeZone || ""}|${iso}`;
  let text = written.get(key);
  if (text === undefined) {
    if (written.size > 20000) written.clear();
    written.set(key, (text = write()));
  }
  return text;
}

export function fmtTime(iso) {
  if (!iso) return "—";
  return remembered("time", iso, () => {
    const p = zoned(iso, {});
    return `${writeDay(p)} ${writeClock(p)}${writeZone(p)}`;
  });
}
/* Time of day only: in the segment list the date is the leg's and would push
   duration and distance out of sight on a laptop; the full time is the title. */
export const fmtClock = (iso) => (iso ? remembered("clock", iso, () => writeClock(zoned(iso, { timeZoneName: undefined }))) : "—");
export const fmtDay = (iso) => (iso ? writeDay(parts(iso, {})) : "");

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
  return formatter("number", fixed).format(value);
}

/* ROS floats are 32-bit: 0.10000000149011612 is shown as 0.1. */
export const roundFloat = (v) => (typeof v === "number" ? Number(v.toPrecision(7)) : v);
