"""Schema-driven fuzzing: every /api/ operation, with a token of the role that may write
there (administrator for configuration and catalogues, operator for the rest), with inputs
generated from the OpenAPI schema (valid and invalid). No answer may be a 5xx, and no
input may reach the database unchecked (the handler's generic "cannot store" 400)."""

import json
import os
import zlib

import pytest
import schemathesis
from django.core import signals
from django.db import close_old_connections
from drf_spectacular.generators import SchemaGenerator
from drf_spectacular.renderers import OpenApiJsonRenderer
from hypothesis import HealthCheck, settings
from schemathesis.checks import not_a_server_error
from schemathesis.config import SchemathesisConfig

from common import roles
from events.models import Leg, SegmentType
from events.services import logs, notes, segments
from ftt_site.wsgi import application
from telemetry.services import attachments
from tests.support.images import jpeg
from tests.support.modes import start_auto

# Small enough that the whole run stays well under two minutes on the CI machine.
MAX_EXAMPLES = 8

CONFIG = SchemathesisConfig.from_dict(
    {"phases": {"coverage": {"enabled": os.environ.get("FTT_FUZZ_COVERAGE") == "1"}}}
)

DB_ERROR = "The request contains a value the database cannot store."


def _openapi() -> dict:
    """The document /api/schema/ serves, generated without a request, so the schema
    is loaded when the module is collected."""
    document = SchemaGenerator().get_schema(request=None, public=True)
    return json.loads(OpenApiJsonRenderer().render(document))


@pytest.fixture(autouse=True)
def _handler_keeps_the_test_transaction(db):
    # Requests go through the real WSGI handler, which closes the database connection
    # after each request; that would end the test's transaction (Django's own test
    # client disconnects the same handlers).
    signals.request_started.disconnect(close_old_connections)
    signals.request_finished.disconnect(close_old_connections)
    yield
    signals.request_started.connect(close_old_connections)
    signals.request_finished.connect(close_old_connections)


# The endpoints of this package (see events/api/urls.py, telemetry/api/urls.py). Archives,
# backups and reports have their own tests; they run real exports and PDF jobs.
OWN_PATHS = (
    r"^/api/(token|test-events|shifts|legs|segments|notes|personnel|performers|vehicles"
    r"|pose-sources|weather|ito-reasons|segment-types|poses|local-poses|maps|images|tracks"
    r"|local-tracks)/"
)
# Every operation is a case of one test with one node id: xdist would run one.
pytestmark = pytest.mark.serial

schema = schemathesis.openapi.from_dict(_openapi(), config=CONFIG).include(path_regex=OWN_PATHS)


@schemathesis.check
def no_unchecked_database_error(ctx, response, case):
    """A value the serializers let through and the database refused is a bug too."""
    if response.status_code == 400 and DB_ERROR in response.text:
        raise AssertionError(f"unvalidated input reached the database: {case.body!r}")


# Only administrators write these; fuzzing them as an operator would stop at the 403.
ADMIN_RESOURCES = {
    "personnel",
    "performers",
    "vehicles",
    "pose-sources",
    "weather",
    "ito-reasons",
    "segment-types",
}


@pytest.fixture
def tokens(role_user):
    return {role: role_user(role).auth_token.key for role in (roles.OPERATOR, roles.ADMINISTRATOR)}


@pytest.fixture
def real_ids(vehicle, performer, person, pose_source, media_root):
    """Ids of existing rows per resource, so that fuzzed bodies also reach real objects.

    Fuzzed DELETEs and closes use them up, so a fresh open chain is made whenever the
    last one is gone or closed.
    """
    current = {}

    def ids():
        if current and Leg.objects.filter(pk=current["legs"], end__isnull=True).exists():
            return current
        event = logs.create_test_event(location="fuzz")
        shift = logs.create_shift(
            test_event=event, vehicle=vehicle, performer=performer, robot_operator=person
        )
        leg = logs.create_leg(shift=shift, default_pose_source=pose_source)
        auto = start_auto(leg)
        ito = segments.report_mode(leg, SegmentType.ITO).master
        child = ito.children.get()
        current.update(
            {
                "test-events": event.pk,
                "shifts": shift.pk,
                "legs": leg.pk,
                "segments": [auto.pk, ito.pk, child.pk],
                "notes": notes.add_note(child, text="fuzz").pk,
                "images": attachments.attach_image(ito, content=jpeg(1)).pk,
                "vehicles": vehicle.key,
                "personnel": person.pk,
                "performers": performer.pk,
                "pose-sources": pose_source.pk,
                "weather": "sunny",
                "ito-reasons": "safety",
                "segment-types": "ito",
            }
        )
        return current

    return ids


@schema.parametrize()
@settings(
    max_examples=MAX_EXAMPLES,
    deadline=None,
    derandomize=True,
    suppress_health_check=list(HealthCheck),
)
def test_no_input_makes_a_server_error(case, tokens, real_ids):
    resource = case.operation.path.split("/")[2]
    path_id = (case.path_parameters or {}).get("id")
    # Three times in four the fuzzed body goes to a real row, so actions get past the 404.
    pick = zlib.crc32(str(path_id).encode())
    if path_id is not None and pick % 4:
        real = real_ids().get(resource, path_id)
        case.path_parameters["id"] = real[pick % len(real)] if isinstance(real, list) else real
    role = roles.ADMINISTRATOR if resource in ADMIN_RESOURCES else roles.OPERATOR
    case.call_and_validate(
        app=application,
        headers={"Authorization": f"Token {tokens[role]}"},
        checks=[not_a_server_error, no_unchecked_database_error],
    )
