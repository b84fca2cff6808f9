"""Fixtures shared by every test package: configuration rows and an open log chain."""

import pytest
from django.conf import settings
from django.core.cache import cache
from django.db import connection
from django.test import override_settings
from django.utils import translation

from events import seeds
from events.models import Performer, Personnel, PoseSource, TestEvent, Vehicle
from events.services import logs
from events.services.robots import ensure_robot_account
from live import wakeup
from tests.support.caches import forget_memos
from tests.support.databases import place_migrated_embedded_database, use_migrated_template
from tests.support.modes import start_auto
from tests.support.snapshot import snapshot
from tests.support.workers import assign_worker_resources

QUICK_PBKDF2 = "tests.support.accounts.QuickPBKDF2PasswordHasher"
EMBEDDED_COPY = pytest.StashKey[bool]()


def pytest_configure(config):
    # Before a test module imports rclpy or reads the Redis URL.
    assign_worker_resources()
    # Before pytest-django creates the test database.
    use_migrated_template()


def pytest_collection_modifyitems(items):
    # xdist hands out whole files in this order: the ROS files, which start
    # collectors and take longest, go first, so that short files fill the end
    # instead of one worker finishing a drill alone. Stable: pytest-django's
    # order holds within each group.
    items.sort(key=lambda item: item.get_closest_marker("ros") is None)


def pytest_runtest_setup(item):
    if item.get_closest_marker("postgis_only") and connection.vendor != "postgresql":
        pytest.skip("needs PostgreSQL (row locks, parallel writers)")


@pytest.fixture(scope="session")
def django_db_modify_db_settings(django_db_modify_db_settings_parallel_suffix, request):
    """pytest-django's hook before it creates the test database, after it named it."""
    request.config.stash[EMBEDDED_COPY] = place_migrated_embedded_database()


@pytest.fixture(scope="session")
def django_db_keepdb(request, django_db_modify_db_settings):
    """The embedded test database copied into place is used as it is."""
    return request.config.getvalue("reuse_db") or request.config.stash[EMBEDDED_COPY]


@pytest.fixture(scope="session", autouse=True)
def _seeds_after_every_flush():
    """A transactional test ends by flushing the database, seeded catalogues and
    roles included, and under xdist any kind of test may come next on the worker.
    The flush sends post_migrate; put back then what ``migrate`` gives a real install."""
    from django.apps import apps
    from django.db.models.signals import post_migrate

    def reseed(**kwargs):
        seeds.seed_catalogues(apps)
        seeds.mark_quick_reasons(apps)
        seeds.create_roles(apps)

    sender = apps.get_app_config("events")
    post_migrate.connect(reseed, sender=sender, weak=False, dispatch_uid="ftt-tests-reseed")
    yield
    post_migrate.disconnect(sender=sender, dispatch_uid="ftt-tests-reseed")


@pytest.fixture(autouse=True)
def _live_link_closed(request):
    """A transactional test's wake-up connection would keep the test database
    from being dropped."""
    marker = request.node.get_closest_marker("django_db")
    if marker and marker.kwargs.get("transaction"):
        request.getfixturevalue("transactional_db")
        yield
        wakeup.send_due_and_close()
    else:
        yield


@pytest.fixture(scope="session", autouse=True)
def _quick_password_hashes():
    """Django's million PBKDF2 rounds are meant to be slow, and the tests make
    hundreds of accounts; a thousand rounds make the same kind of hash, which the
    servers the tests start check as they check any other."""
    with override_settings(PASSWORD_HASHERS=[QUICK_PBKDF2, *settings.PASSWORD_HASHERS]):
        yield


@pytest.fixture(autouse=True)
def _fresh_throttles():
    """API throttles count in the cache; each test starts with none used up."""
    cache.clear()


@pytest.fixture(autouse=True)
def _site_language():
    """A request through the test client leaves its language active in the
    thread (Django's LocaleMiddleware activates, never resets): each test starts
    in the site's language."""
    translation.activate(settings.LANGUAGE_CODE)
    yield
    translation.activate(settings.LANGUAGE_CODE)


@pytest.fixture(autouse=True)
def _fresh_memos():
    forget_memos()


@pytest.fixture
def media_root(settings, tmp_path):
    settings.MEDIA_ROOT = tmp_path / "media"
    return settings.MEDIA_ROOT


@pytest.fixture
def vehicle(db):
    return Vehicle.objects.create(key="husky", short_description="Husky A200", institution="FKIE")


@pytest.fixture
def other_vehicle(db):
    return Vehicle.objects.create(key="jackal", short_description="Jackal", institution="FKIE")


@pytest.fixture
def performer(db):
    return Performer.objects.create(institution="Fraunhofer FKIE")


@pytest.fixture
def person(db):
    return Personnel.objects.create(name="Jörg Müller", institution="FKIE")


@pytest.fixture
def pose_source(db):
    return PoseSource.objects.create(key="gps", short_description="RTK GPS")


@pytest.fixture
def test_event(db):
    return logs.create_test_event(location="Wachtberg", version="1.0", time_zone="Europe/Berlin")


@pytest.fixture
def shift(test_event, vehicle, performer, person):
    return logs.create_shift(
        test_event=test_event, vehicle=vehicle, performer=performer, robot_operator=person
    )


@pytest.fixture
def leg(shift, pose_source):
    return logs.create_leg(shift=shift, default_pose_source=pose_source, weather_id="sunny")


@pytest.fixture
def other_leg(test_event, other_vehicle, pose_source):
    """An open leg of the other vehicle, in the same test event."""
    other_shift = logs.create_shift(test_event=test_event, vehicle=other_vehicle)
    return logs.create_leg(shift=other_shift, default_pose_source=pose_source)


@pytest.fixture
def auto_master(leg):
    """The AUTO master segment a robot's first mode report opens on ``leg``."""
    return start_auto(leg)


# --- API users: one per role, each with a token (tests/events/api, tests/telemetry/api) ---


@pytest.fixture
def role_user(db, django_user_model):
    """role_user("operator") -> a user in that group (None: no role at all), with a token."""
    from django.contrib.auth.models import Group
    from rest_framework.authtoken.models import Token

    made = []

    def make(role):
        made.append(role)
        name = f"{role or 'norole'}-{len(made)}"
        user = django_user_model.objects.create_user(name, password="pw")
        if role:
            user.groups.add(Group.objects.get(name=role))
        Token.objects.create(user=user)
        return user

    return make


@pytest.fixture
def api_client(role_user):
    """api_client("viewer") -> a DRF client sending that user's token (None: anonymous);
    the client's ``user`` and ``token`` say whose."""
    from rest_framework.test import APIClient

    def make(role="operator", *, anonymous=False):
        client = APIClient()
        if not anonymous:
            user = role_user(role)
            client.credentials(HTTP_AUTHORIZATION=f"Token {user.auth_token.key}")
            client.user = user
            client.token = user.auth_token.key
        return client

    return make


@pytest.fixture
def robot_client(db):
    """robot_client(vehicle, ...) -> a DRF client with the token of a robot account
    bound to those vehicles (none: bound to no vehicle); the client's ``user`` and
    ``token`` say whose."""
    from rest_framework.test import APIClient

    made = []

    def make(*vehicles):
        made.append(vehicles)
        login = ensure_robot_account(f"robot-{len(made)}", list(vehicles))
        client = APIClient()
        client.credentials(HTTP_AUTHORIZATION=f"Token {login.token}")
        client.user = login.account.user
        client.token = login.token
        return client

    return make


@pytest.fixture
def wipe():
    """Forget everything, as on a freshly installed base station (catalogues stay)."""

    def _wipe():
        TestEvent.objects.all().delete()
        for model in (Vehicle, PoseSource, Performer, Personnel):
            model.objects.all().delete()
        assert all(not rows for rows in snapshot().values())

    return _wipe
