/* The open leg's test case in the cockpit: its title, its progress line
 * ("run 2 of 3 · 312 m of 500 m without intervention") and its criteria with
 * their verdicts, all as the server's test plan (GET /api/reports/test-plan/)
 * says; refreshed at most every few seconds while the robot drives. */
import { $ } from "./dom.js";
import { api } from "./api.js";
import { showError } from "./feedback.js";
import { current, state } from "./state.js";
import { _ } from "./i18n.js";

const PAUSE_MS = 2000; // the plan reads the whole event's figures: not on every pose

/* A verdict (the server's value) in the page's language. */
function verdictWord(verdict) {
  const words = { pass: _("pass"), fail: _("fail"), "not yet": _("not yet"), "needs a judgement": _("needs a judgement") };
  return words[verdict] ?? verdict;
}

export const TestPlan = {
  timer: null,
  last: 0,
  /* Asks for a refresh; bursts of segment and pose events become one read. */
  later() {
    if (this.timer) return;
    const wait = Math.max(0, this.last + PAUSE_MS - Date.now());
    this.timer = setTimeout(() => {
      this.timer = null;
      this.last = Date.now();
      this.refresh().catch(showError);
    }, wait);
  },
  async refresh() {
    const leg = current("leg");
    const box = $("#test-case");
    if (!leg || !leg.test_case || !state.selected.event) {
      box.hidden = true;
      return;
    }
    const asked = leg.id;
    const plan = await api("GET", `reports/test-plan/${state.selected.event}/`);
    if (state.selected.leg !== asked) return; // another leg was chosen meanwhile
    const found = plan.cases.find((c) => c.test_case === leg.test_case);
    box.hidden = !found;
    if (!found) return;
    $("#test-case-title").textContent = `${found.key}: ${found.title}`;
    $("#test-case-progress").textContent = found.progress;
    const own = found.legs.find((l) => l.leg === leg.id);
    // The leg's own verdicts where the criterion is judged per leg, else the case's.
    const byCriterion = new Map(found.verdicts.map((v) => [v.criterion, v]));
    for (const v of own ? own.verdicts : []) byCriterion.set(v.criterion, v);
    $("#test-case-criteria").replaceChildren(
      ...[...byCriterion.values()].map((v) => {
        const item = document.createElement("li");
        item.dataset.verdict = v.verdict;
        const verdict = document.createElement("span");
        verdict.className = "verdict";
        verdict.textContent = verdictWord(v.verdict);
        item.append(`${v.text} `, verdict);
        return item;
      }),
    );
  },
};
