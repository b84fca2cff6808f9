"""What comparing long routes costs: two legs of 2 000 fixes each are compared
within seconds, a leg longer than the comparison's point budget is compared
simplified (and the answer says at what tolerance), and one request compares a
bounded number of routes."""

import time

import numpy as np
import pytest
import shapely

from common import roles
from reports.selectors import routes
from tests.reports.test_route_comparison import GEOD, drive

# About 1.5 m between fixes, wandering like a GPS track driven off any straight line.
DEGREES_PER_METRE = 1 / 111_000


def wander(seed: int, count: int) -> list[tuple[float, float]]:
    steps = np.random.default_rng(seed).normal(scale=1.5 * DEGREES_PER_METRE, size=(count, 2))
    points = np.cumsum(steps, axis=0) + (7.1, 50.6)
    return [tuple(p) for p in points.tolist()]


def test_two_legs_of_two_thousand_fixes_are_compared_within_seconds(api_client, shift):
    first, second = drive(shift, wander(1, 2000)), drive(shift, wander(2, 2000))
    started = time.monotonic()
    response = api_client(roles.VIEWER).get("/api/reports/routes/", {"leg": [first.pk, second.pk]})
    elapsed = time.monotonic() - started
    assert response.status_code == 200, response.content
    assert elapsed < 20, elapsed
    answer = response.json()
    assert [len(points) for points in answer["routes"].values()] == [2000, 2000]
    assert answer["simplified"] == {}
    assert answer["pairs"][0]["frechet"] > 0


def test_the_frechet_distance_is_the_same_as_geos_gives():
    rng = np.random.default_rng(7)
    for n, m in ((2, 2), (2, 90), (90, 2), (40, 130), (200, 170)):
        a = np.cumsum(rng.normal(size=(n, 2)), axis=0)
        b = np.cumsum(rng.normal(size=(m, 2)), axis=0)
        expected = shapely.frechet_distance(shapely.linestrings(a), shapely.linestrings(b))
        assert routes.discrete_frechet(a, b) == pytest.approx(expected, rel=1e-12)


def test_a_leg_over_the_point_budget_is_compared_simplified(api_client, shift):
    budget = 300
    long = drive(shift, wander(3, 1000))
    short = drive(shift, wander(4, 200))
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(routes, "MAX_POINTS", budget)
        response = api_client(roles.VIEWER).get(
            "/api/reports/routes/", {"leg": [long.pk, short.pk]}
        )
    assert response.status_code == 200, response.content
    answer = response.json()
    assert len(answer["routes"][f"leg {long.pk}"]) <= budget
    assert len(answer["routes"][f"leg {short.pk}"]) == 200
    assert answer["simplified"][f"leg {long.pk}"] > 0
    assert f"leg {short.pk}" not in answer["simplified"]


def test_one_request_compares_a_bounded_number_of_routes(api_client, shift):
    leg = drive(shift, wander(5, 20))
    many = {"leg": [leg.pk] * (routes.MAX_ROUTES + 1)}
    response = api_client(roles.VIEWER).get("/api/reports/routes/", many)
    assert response.status_code == 400
    assert "at most" in " ".join(response.json()["errors"]["leg"])


def test_long_routes_are_compared_within_seconds_and_still_measured_right(api_client, shift):
    """Legs above the point budget are simplified, and the figures still say what
    the routes are: a route against itself is 0 m off, a copy moved 5 m north 5 m."""
    points = wander(6, routes.MAX_POINTS + 1000)
    north = 5 * DEGREES_PER_METRE
    original = drive(shift, points)
    same = drive(shift, points)
    moved = drive(shift, [(lon, lat + north) for lon, lat in points])
    client = api_client(roles.VIEWER)
    started = time.monotonic()
    alike = client.get("/api/reports/routes/", {"leg": [original.pk, same.pk]})
    apart = client.get("/api/reports/routes/", {"leg": [original.pk, moved.pk]})
    elapsed = time.monotonic() - started
    assert alike.status_code == apart.status_code == 200, (alike.content, apart.content)
    assert elapsed < 20, elapsed
    alike, apart = alike.json(), apart.json()
    assert all(len(p) <= routes.MAX_POINTS for p in [*alike["routes"].values()])
    assert alike["pairs"][0]["frechet"] == pytest.approx(0, abs=1e-6)
    assert alike["pairs"][0]["deviation"][f"leg {same.pk}"]["max"] == pytest.approx(0, abs=1e-6)
    # Both simplified at the tolerance named, so the shift is known to within it.
    tolerance = max(apart["simplified"].values())
    shifted = GEOD.inv(*points[0], points[0][0], points[0][1] + north)[2]
    assert apart["pairs"][0]["frechet"] == pytest.approx(shifted, abs=tolerance + 0.05)
