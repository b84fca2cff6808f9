"""Reliability across test events: figures side by side and the growth fit,
checked against values worked out by hand for two copies of the scenario."""

import math
import re

import numpy as np
import pytest
from django.core.management import CommandError, call_command

from reports.models import Report
from reports.selectors.growth import crow_amsaa
from reports.selectors.hotspots import HOTSPOT_RADIUS_M, cluster_labels
from reports.services.generation import run_job
from tests.support.pdf import flat, pdf_text
from tests.support.scenario import STEP_M, build_scenario, chi2_quantile_even


def _reference_beta(at, total):
    """β maximising the NHPP log-likelihood with λ = n / T^β, by golden-section
    search on the log-likelihood itself (not the closed form under test)."""
    n = len(at)

    def loglik(beta):
        lam = n / total**beta
        return n * math.log(lam * beta) + (beta - 1) * sum(math.log(t) for t in at) - n

    lo, hi = 0.01, 10.0
    ratio = (math.sqrt(5) - 1) / 2
    for _ in range(200):
        a, b = hi - ratio * (hi - lo), lo + ratio * (hi - lo)
        lo, hi = (lo, b) if loglik(a) > loglik(b) else (a, hi)
    return (lo + hi) / 2


def test_crow_amsaa_fit_and_bounds_match_an_independent_reference():
    at = [3.0, 13.0, 16.0, 26.0]
    fit = crow_amsaa(at, 26.0)
    beta = _reference_beta(at, 26.0)
    assert fit.beta == pytest.approx(beta, rel=1e-6)
    assert fit.lam == pytest.approx(4 / 26.0**beta, rel=1e-6)
    assert fit.growth == pytest.approx(1 - beta, rel=1e-6)
    # 90 %: chi-square quantiles with 2n = 8 degrees of freedom, closed-form CDF.
    assert fit.beta_lower == pytest.approx(beta * chi2_quantile_even(0.05, 8) / 8, rel=1e-6)
    assert fit.beta_upper == pytest.approx(beta * chi2_quantile_even(0.95, 8) / 8, rel=1e-6)
    assert fit.expected(26.0) == pytest.approx(4.0)
    assert fit.expected(13.0, fit.beta_lower) > fit.expected(13.0, fit.beta_upper)
    assert crow_amsaa([5.0], 26.0) is None


@pytest.fixture
def two_events(vehicle, other_vehicle, performer, media_root):
    first = build_scenario(vehicle, other_vehicle, performer, text="v1")
    second = build_scenario(vehicle, other_vehicle, performer, text="v2")
    return first, second


def test_comparison_over_the_api_matches_hand_computed_figures(two_events, api_client):
    first, second = two_events
    url = f"/api/reports/compare/?test_event={first.event.pk}&test_event={second.event.pk}"
    response = api_client("viewer").get(url)
    assert response.status_code == 200
    data = response.json()
    # Each copy: 13 steps autonomous, interventions I1 (after 3 steps) and I3 (after 13).
    for row in data["test_events"]:
        figures = row["figures"]
        assert figures["interventions"] == 2
        assert figures["auto_distance"] == pytest.approx(13 * STEP_M)
        assert figures["mdbi"]["value"] == pytest.approx(13 * STEP_M / 2)
        assert figures["mdbi"]["lower"] == pytest.approx(
            2 * 13 * STEP_M / chi2_quantile_even(0.95, 6)
        )
        assert figures["interventions_per_km"] == pytest.approx(2 / (13 * STEP_M / 1000))
    assert sorted(v["version"] for v in data["versions"]) == ["v1", "v2"]
    vehicles = {v["name"]: v["figures"]["interventions"] for v in data["vehicles"]}
    # I1 is driven in shift 1 (vehicle), I3 in shift 2 (the other vehicle), in both events.
    assert sorted(vehicles.values()) == [2, 2]
    growth = data["growth"]
    steps = [p["distance"] / STEP_M for p in growth["points"]]
    assert steps == pytest.approx([3, 13, 16, 26])
    assert growth["total_distance"] == pytest.approx(26 * STEP_M)
    beta = 4 / sum(math.log(26 / t) for t in (3, 13, 16, 26))
    assert growth["fit"]["beta"] == pytest.approx(beta)
    assert growth["fit"]["growth"] == pytest.approx(1 - beta)
    # The copies share positions: I1 of both events at 0.003° east, I3 of both at 0.020°,
    # 17 steps apart, far beyond the radius: two hotspots of two take-overs each,
    # numbered by their first take-over (I1 of the first event).
    spots = data["hotspots"]
    assert [s["number"] for s in spots] == [1, 2] and [s["count"] for s in spots] == [2, 2]
    i1 = {first.masters["I1"].id, second.masters["I1"].id}
    i3 = {first.masters["I3"].id, second.masters["I3"].id}
    assert {m["segment"] for m in spots[0]["members"]} == i1
    assert {m["segment"] for m in spots[1]["members"]} == i3
    assert {m["label"] for m in spots[0]["members"]} == {"Leg 1 · #2"}
    assert {m["test_event"] for m in spots[1]["members"]} == {first.event.pk, second.event.pk}
    assert spots[0]["reasons"] == {"planner": 2, "safety": 2}
    assert spots[1]["reasons"] == {"unexpected": 2}
    # On the equator the local frame's east axis is the equator: a * Δλ exactly.
    assert spots[1]["east"] - spots[0]["east"] == pytest.approx(17 * STEP_M, abs=1e-6)
    assert spots[0]["north"] == pytest.approx(0.0, abs=1e-6)
    assert spots[0]["x"] == pytest.approx(0.003) and spots[1]["x"] == pytest.approx(0.020)
    assert "Growth fit" in data["formulas"] and "Take-over hotspots" in data["formulas"]


def test_hotspots_chain_take_overs_at_most_the_radius_apart():
    # Hand-worked: 0-20-40 chain (each step 20 m <= 25 m) although 0 and 40 are 40 m
    # apart; 100-125 are exactly the radius apart; 300/300 and 500/0 stand alone.
    xy = np.array(
        [[0.0, 0.0], [300.0, 300.0], [20.0, 0.0], [100.0, 0.0], [40.0, 0.0], [125.0, 0.0], [500, 0]]
    )
    assert HOTSPOT_RADIUS_M == 25.0
    # Sizes 3, 2, 1, 1; the two single ones by first appearance (300/300 before 500/0).
    assert cluster_labels(xy) == [1, 3, 1, 2, 1, 2, 4]
    # 25.5 m apart is just beyond the radius: two hotspots of one.
    assert cluster_labels(np.array([[0.0, 0.0], [25.5, 0.0]])) == [1, 2]
    # A smaller radius breaks the chain: 0/20/40 become three.
    assert cluster_labels(xy[[0, 2, 4]], radius=10.0) == [1, 2, 3]
    assert cluster_labels(np.empty((0, 2))) == []


def test_comparison_pdf_is_a_job_over_the_api(two_events, api_client, tmp_path):
    first, second = two_events
    operator = api_client("operator")
    response = operator.post(
        "/api/reports/", {"compare": [second.event.pk, first.event.pk]}, format="json"
    )
    assert response.status_code == 202
    body = response.json()
    assert body["kind"] == "comparison" and body["status"] == "queued"
    assert body["compare"] == [first.event.pk, second.event.pk]  # oldest first
    report = run_job(body["id"])
    assert report.status == Report.Status.DONE, report.error
    shown = operator.get(f"/api/reports/{body['id']}/").json()
    assert shown["download"].endswith(f"/api/reports/{body['id']}/pdf/")
    pdf = operator.get(f"/api/reports/{body['id']}/pdf/")
    assert pdf.status_code == 200
    assert "ftt-comparison-" in pdf["Content-Disposition"]
    text = flat(pdf_text(b"".join(pdf.streaming_content), tmp_path))
    assert "Reliability across test events" in text
    # The hotspot table: number, take-overs, reasons with counts, each segment's label.
    assert "Hotspot Take-overs Reasons" in text
    assert "Unexpected (2)" in text or "unexpected (2)" in text
    assert text.count("Leg 1 · #2") >= 2 and text.count("Leg 1 · #4") >= 2


def test_comparison_requests_are_checked_before_queueing(two_events, api_client):
    first, second = two_events
    operator = api_client("operator")
    for body, field in (
        ({"compare": [first.event.pk]}, "compare"),
        ({"compare": [first.event.pk, 99999]}, "compare"),
        ({"compare": [first.event.pk, first.event.pk]}, "compare"),
        ({"compare": [first.event.pk, "x"]}, "compare"),
        ({"test_event": first.event.pk, "compare": [1, 2]}, "test_event"),
        ({}, "test_event"),
        ({"compare": [first.event.pk, second.event.pk], "options": {"level": "full"}}, "options"),
    ):
        response = operator.post("/api/reports/", body, format="json")
        assert response.status_code == 400, body
        assert field in response.json()["errors"], (body, response.json())
    assert (
        api_client("viewer")
        .post("/api/reports/", {"compare": [first.event.pk, second.event.pk]}, format="json")
        .status_code
        == 403
    )
    assert Report.objects.count() == 0


def test_comparison_refuses_fewer_than_two_or_unknown_events(two_events, api_client):
    first, _ = two_events
    client = api_client("viewer")
    one = client.get(f"/api/reports/compare/?test_event={first.event.pk}")
    assert one.status_code == 400 and "at least two" in one.json()["errors"]["test_event"][0]
    unknown = client.get(f"/api/reports/compare/?test_event={first.event.pk}&test_event=99999")
    assert unknown.status_code == 400
    assert "99999" in unknown.json()["errors"]["test_event"][0]


def test_compare_command_writes_a_pdf_with_every_part(two_events, tmp_path):
    first, second = two_events
    out = tmp_path / "cmp.pdf"
    call_command(
        "ftt_report", "--compare", str(first.event.pk), str(second.event.pk), "-o", str(out)
    )
    text = flat(pdf_text(out.read_bytes(), tmp_path))
    for heading in ("Per test event", "Per software version", "Per vehicle", "Reliability growth"):
        assert heading in text, heading
    beta = 4 / sum(math.log(26 / t) for t in (3, 13, 16, 26))
    assert f"β {beta:.3f}" in text
    assert f"Growth parameter 1 − β {1 - beta:.3f}" in text
    assert "Take-over hotspots: where interventions started" in text
    assert "Hotspot Take-overs Reasons" in text
    assert "β = n / Σ ln(T / t_i)" in text
    with pytest.raises(CommandError, match="99999 does not exist"):
        call_command("ftt_report", "--compare", str(first.event.pk), "99999")


def test_the_comparisons_time_names_its_zone(two_events, tmp_path):
    first, second = two_events
    second.event.time_zone = "America/Los_Angeles"
    second.event.save()
    out = tmp_path / "cmp.pdf"
    call_command(
        "ftt_report", "--compare", str(first.event.pk), str(second.event.pk), "-o", str(out)
    )
    text = flat(pdf_text(out.read_bytes(), tmp_path))
    times = re.findall(r"\d\d:\d\d(?::\d\d)? \((\S+)\)", text)
    assert times == [first.event.time_zone] == ["Asia/Tokyo"]
