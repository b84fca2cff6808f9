"""The three screens the GUI is used on, and what the browser tests check on each:
nothing sticks out sideways, every main action is big enough to tap, and axe
finds no accessibility problem."""

from tests.support.browser import ROOT

VIEWPORTS = {
    "laptop": {"viewport": {"width": 1366, "height": 768}},
    "tablet": {"viewport": {"width": 1024, "height": 768}, "has_touch": True, "is_mobile": True},
    "phone": {"viewport": {"width": 390, "height": 844}, "has_touch": True, "is_mobile": True},
}

# Whatever sticks out of the window or scrolls sideways inside its box; the maps'
# panes are clipped by Leaflet on purpose, and a long value scrolls in its input.
OVERFLOWING = """() => {
  const width = document.documentElement.clientWidth;
  const out = [];
  for (const el of document.querySelectorAll("body *")) {
    if (el.closest(".leaflet-container, dialog:not([open])")) continue;
    if (["INPUT", "SELECT", "TEXTAREA", "OPTION"].includes(el.tagName)) continue;
    const r = el.getBoundingClientRect();
    if (!r.width || !r.height) continue;
    const style = getComputedStyle(el);
    const clips = style.overflowX !== "visible";
    if (r.right > width + 0.5 || r.left < -0.5 || (clips && el.scrollWidth > el.clientWidth + 1)) {
      out.push(`${el.tagName.toLowerCase()}#${el.id}.${el.className}`);
    }
  }
  if (document.documentElement.scrollWidth > width) out.push("page");
  return out;
}"""

SMALL = """(selector) => Array.from(document.querySelectorAll(selector))
  .filter((el) => el.getClientRects().length && !el.closest("[hidden]"))
  .map((el) => [el.id || el.textContent.trim().slice(0, 20), el.getBoundingClientRect()])
  .filter(([, r]) => r.height < 44 || r.width < 44)
  .map(([name, r]) => `${name}: ${Math.round(r.width)}x${Math.round(r.height)}`)"""

# axe-core from npm (scripts/setup.sh --test).
AXE = ROOT / "node_modules" / "axe-core" / "axe.min.js"

# Every violation of any impact, with the experimental check that a control's
# accessible name contains its visible text (speech users say what they see).
VIOLATIONS = """async () => {
  const result = await axe.run(document, {
    resultTypes: ["violations"],
    rules: { "label-content-name-mismatch": { enabled: true } },
  });
  return result.violations.map(
    (v) => `${v.id} (${v.impact}): ${v.nodes.map((n) => n.target.join(" ")).join(", ")}`);
}"""
