/* Route comparison on the comparison page: two legs' GPS routes (or a leg and a
 * test case's planned route) on one map,
 * per pair the deviation of each from the other (mean, 95th percentile,
 * maximum, share beyond the threshold), the discrete Fréchet distance, and the
 * stretches beyond the threshold in red.  GET /api/reports/routes/ computes it all. */
import { CONFIG, $, element } from "./dom.js";
import { api, list, plainMessage } from "./api.js";
import { latLngs, plainMap } from "./comparemap.js";
import { _ } from "./i18n.js";
import { fmtNumber } from "./format.js";

const COLOURS = ["#1f5fbf", "#e07b00"];
const BEYOND = "#d00000";
const routes = { map: null, drawn: null, shown: null };

/* The routes of the comparison on screen, as a comparison PDF asks for them
 * ({leg: [ids], case: [ids], threshold}), or null before one was drawn: the
 * PDF button (compare.js) sends them, so the PDF shows what the screen shows. */
export const shownRoutes = () => routes.shown;

function say(text, isError = false) {
  const line = $("#routes-status");
  line.textContent = text;
  line.classList.toggle("error", isError);
}

const metres = (value) => `${fmtNumber(value, 1)} m`;

/* Routes are A and B on the map, in the legend and in the figures. */
const LETTERS = ["A", "B"];

function pairCard(pair, names) {
  const rows = [[_("Discrete Fréchet distance"), metres(pair.frechet)]];
  for (const name of pair.routes) {
    const d = pair.deviation[name];
    const other = pair.routes.find((n) => n !== name);
    rows.push(
      [_("%(route)s from %(other)s: mean", { route: names[name].letter, other: names[other].letter }), metres(d.mean)],
      [_("95th percentile"), metres(d.p95)],
      [_("maximum"), metres(d.max)],
      [_("beyond the threshold"), _("%(share)s of its points", { share: `${Math.round(d.share_beyond * 100)} %` })],
    );
  }
  return element("article", { className: "card route-pair" }, [
    element("h3", { textContent: _("%(first)s and %(second)s", { first: names[pair.routes[0]].letter, second: names[pair.routes[1]].letter }) }),
    element("dl", { className: "pairs" }, rows.flatMap(([k, v]) => [element("dt", { textContent: k }), element("dd", { textContent: v })])),
  ]);
}

function draw(data, names) {
  $("#routes-map").hidden = false;
  if (!routes.map) routes.map = plainMap($("#routes-map"));
  routes.map.invalidateSize();
  if (routes.drawn) routes.drawn.remove();
  routes.drawn = L.featureGroup().addTo(routes.map);
  // Wide route lines with the red stretches narrower on top: both stay visible.
  Object.entries(data.routes).forEach(([name, points]) => {
    L.polyline(latLngs(points), { color: names[name].colour, weight: 9, opacity: 0.75 })
      .bindTooltip(element("span", { textContent: `${names[name].letter}: ${names[name].text}` }))
      .addTo(routes.drawn);
  });
  for (const pair of data.pairs) {
    for (const name of pair.routes) {
      for (const stretch of pair.deviation[name].beyond) {
        L.polyline(latLngs(stretch), { color: BEYOND, weight: 3, opacity: 1, className: "beyond" })
          .bindTooltip(element("span", { textContent: _("%(route)s: more than %(metres)s m off", { route: names[name].letter, metres: data.threshold }) }))
          .addTo(routes.drawn);
      }
    }
  }
  routes.map.fitBounds(routes.drawn.getBounds(), { padding: [20, 20] });
  const key = (colour, text) => element("li", {}, [element("span", { className: "swatch", style: `background:${colour}` }), text]);
  $("#routes-legend").replaceChildren(
    ...Object.values(names).map((n) => key(n.colour, `${n.letter}: ${n.text}`)),
    key(BEYOND, _("more than %(metres)s m from the other route", { metres: data.threshold })),
  );
  $("#routes-figures").replaceChildren(...data.pairs.map((pair) => pairCard(pair, names)));
}

/* A picker's value: a leg's id, or "case:<id>" for a test case's planned route. */
function routeOf(select) {
  const [kind, id] = select.value.startsWith("case:") ? ["case", select.value.slice(5)] : ["leg", select.value];
  return { param: [kind, id], name: `${kind} ${id}` };
}

async function compare(e) {
  e.preventDefault();
  const form = $("#routes-form").elements;
  const [a, b] = [form.leg_a, form.leg_b];
  const chosen = [a, b].map(routeOf);
  const q = new URLSearchParams([...chosen.map((r) => r.param), ["threshold", form.threshold.value]]);
  // The server names routes "leg <id>" and "case <id>"; the page shows A and B with the picker's words.
  const names = Object.fromEntries(
    chosen.map((route, i) => [route.name, { letter: LETTERS[i], colour: COLOURS[i], text: [a, b][i].selectedOptions[0].textContent }]),
  );
  say(_("Comparing the routes…"));
  try {
    const data = await api("GET", `reports/routes/?${q}`);
    draw(data, names);
    // Ids as the server took them; legs before cases, the order the server names routes in.
    const ids = (kind) => chosen.filter((r) => r.param[0] === kind).map((r) => Number(r.param[1]));
    routes.shown = { leg: ids("leg"), case: ids("case"), threshold: data.threshold };
    say(_("Routes compared; threshold %(metres)s m.", { metres: data.threshold }));
  } catch (err) {
    say(plainMessage(err), true);
  }
}

async function main() {
  $("#routes-form").addEventListener("submit", compare);
  try {
    const [legs, shifts, planned] = await Promise.all([
      list("legs/"),
      list("shifts/"),
      api("GET", "test-case-routes/", undefined, { root: CONFIG.guiApiRoot }),
    ]);
    const shiftOf = new Map(shifts.map((s) => [s.id, s]));
    legs.sort((x, y) => (x.start < y.start ? 1 : -1));
    const options = legs.map((leg) => {
      const shift = shiftOf.get(leg.shift);
      const where = shift ? `#${shift.test_event} · ${_("Shift %(number)s", { number: shift.number })} · ` : "";
      return new Option(`${where}${_("Leg %(number)s", { number: leg.number })} (${(leg.start || "").slice(0, 10)})`, leg.id);
    });
    const form = $("#routes-form").elements;
    form.leg_a.replaceChildren(...options);
    form.leg_b.replaceChildren(...options.map((o) => o.cloneNode(true)));
    if (planned.cases.length) {
      const group = element("optgroup", { label: _("Planned routes of test cases") });
      group.append(...planned.cases.map((c) => new Option(_("#%(event)s %(key)s: %(title)s (planned)", { event: c.test_event, key: c.key, title: c.title }), `case:${c.id}`)));
      form.leg_b.append(group);
    }
    if (options.length > 1) form.leg_b.selectedIndex = 1;
  } catch (err) {
    say(plainMessage(err), true);
  }
}

if ($("#routes-form")) main();
