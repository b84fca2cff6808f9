"""Archives from elsewhere are hostile until proven otherwise: zip bombs, files
posing as photos and malformed manifests or records are refused with a message
(400), never a server error, and nothing is imported."""

import io
import json
import struct
import zipfile

import pytest
from django.core.files.uploadedfile import SimpleUploadedFile
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from events.models import TestEvent, Vehicle
from exchange.archive import ArchiveError, open_archive
from telemetry.models import Image
from tests.support.api import download
from tests.support.archives import members_of, replace_record, signed_archive
from tests.support.field_day import field_day
from tests.support.jobs import run_queued_jobs
from tests.support.snapshot import snapshot

pytestmark = pytest.mark.django_db


@pytest.fixture
def exported(api_client, media_root, wipe):
    """The members of a field day's archive, with the installation emptied again."""
    data = download(api_client("viewer"), field_day())
    wipe()
    return members_of(data)


@pytest.fixture
def post(api_client):
    admin = api_client("administrator")

    def send(data: bytes):
        return admin.post(
            "/api/archives/import/", {"archive": io.BytesIO(data)}, format="multipart"
        )

    return send


def _with_image(members: dict[str, bytes], name: str, body: bytes) -> dict[str, bytes]:
    old = next(n for n in members if n.startswith("files/images/"))
    changed = {n: b for n, b in members.items() if n != old}
    changed[f"files/{name}"] = body
    return replace_record(changed, "images", lambda r: {**r, "file": name})


def test_a_web_page_posing_as_an_image_is_refused(exported, post):
    page = b"<html><script>alert(document.cookie)</script></html>"
    response = post(signed_archive(_with_image(exported, "images/x/evil.html", page)))
    assert response.status_code == 400
    assert "Not a readable JPEG/PNG/WEBP image" in response.json()["detail"]
    assert not any(snapshot().values())


def test_a_real_picture_gets_the_extension_of_its_format(exported, post, media_root):
    png = exported[next(n for n in exported if n.startswith("files/maps/"))]
    response = post(signed_archive(_with_image(exported, "images/x/photo.html", png)))
    assert response.status_code == 202, response.json()
    run_queued_jobs()
    stored = Image.objects.get().image.name
    assert stored.endswith(".png") and (media_root / stored).read_bytes() == png


def test_an_eps_photo_is_refused(exported, post):
    eps = b"%!PS-Adobe-3.0 EPSF-3.0\n%%BoundingBox: 0 0 10 10\nshowpage\n"
    response = post(signed_archive(_with_image(exported, "images/x/photo.eps", eps)))
    assert response.status_code == 400
    assert not TestEvent.objects.exists()


def _archive_file(tmp_path, members: dict[str, bytes]):
    path = tmp_path / "a.zip"
    path.write_bytes(signed_archive(members))
    return path


@pytest.mark.parametrize(
    "limit, value, members",
    [
        ("FTT_ARCHIVE_MAX_MEMBER_BYTES", 1024**2, {"data/x.jsonl": bytes(2 * 1024**2)}),
        ("FTT_ARCHIVE_MAX_TOTAL_BYTES", 1024**2, {f"data/{i}": bytes(600_000) for i in "ab"}),
        ("FTT_ARCHIVE_MAX_MEMBERS", 3, {f"data/{i}": b"{}" for i in "abcd"}),
        ("FTT_ARCHIVE_MAX_RATIO", 200, {"data/zeros.jsonl": bytes(20 * 1024**2)}),
    ],
    ids=["member-size", "total-size", "member-count", "ratio"],
)
def test_zip_bombs_are_refused_by_configurable_limits(tmp_path, settings, limit, value, members):
    setattr(settings, limit, value)
    with pytest.raises(ArchiveError, match=f"\\({limit}\\)"):
        open_archive(_archive_file(tmp_path, members))


def test_a_member_larger_than_its_directory_entry_says_is_cut_off(tmp_path, settings):
    """The limits hold even if the zip directory lies about a member's size."""
    settings.FTT_ARCHIVE_MAX_MEMBER_BYTES = 1024**2
    path = _archive_file(tmp_path, {"data/x.jsonl": bytes(4 * 1024**2)})
    data = bytearray(path.read_bytes())
    with zipfile.ZipFile(path) as z:
        info = z.getinfo("data/x.jsonl")
    # Patch the uncompressed size in the local header and the central directory to 1 KiB.
    lied = (1024).to_bytes(4, "little")
    true = info.file_size.to_bytes(4, "little")
    data[:] = data.replace(true, lied)
    path.write_bytes(bytes(data))
    with pytest.raises(ArchiveError):
        open_archive(path)


MALFORMED = {
    "manifest-a-list": lambda m: signed_archive(m, {"members": list(m)}),
    "member-entry-a-list": lambda m: signed_archive(m, {"members": {n: [] for n in m}}),
    "uid-a-number": lambda m: signed_archive(
        replace_record(m, "shifts", lambda r: {**r, "uid": 7})
    ),
    "uid-a-list": lambda m: signed_archive(replace_record(m, "legs", lambda r: {**r, "uid": [1]})),
    "file-a-dict": lambda m: signed_archive(replace_record(m, "maps", lambda r: {**r, "file": {}})),
    "history-channel-unknown": lambda m: signed_archive(
        replace_record(m, "history", lambda r: {**r, "channel": "fax"})
    ),
    "history-reference-a-number": lambda m: signed_archive(
        replace_record(m, "history", lambda r: {**r, "values": {**r["values"], "leg": 7}})
    ),
    "history-without-time": lambda m: signed_archive(
        replace_record(m, "history", lambda r: {**r, "at": None})
    ),
    "vehicle-without-name": lambda m: signed_archive(
        replace_record(m, "vehicles", lambda r: _without(r, "short_description"))
    ),
}


def _without(record: dict, field: str) -> dict:
    return {k: v for k, v in record.items() if k != field}


def test_an_archive_from_before_the_vin_imports_its_vehicles_without_one(exported, post):
    response = post(
        signed_archive(replace_record(exported, "vehicles", lambda r: _without(r, "vin")))
    )
    assert response.status_code == 202, response.json()
    run_queued_jobs()
    assert list(Vehicle.objects.values_list("vin", flat=True)) == [""]


@pytest.mark.parametrize("build", MALFORMED.values(), ids=MALFORMED.keys())
def test_malformed_manifest_or_record_is_400_with_a_message(exported, post, build):
    response = post(build(exported))
    assert response.status_code == 400
    assert response.json()["detail"]
    assert not any(snapshot().values())


@pytest.mark.parametrize("shape", ["member-entry-a-list", "uid-a-number"])
def test_the_import_page_explains_a_malformed_archive(exported, client, role_user, shape):
    client.force_login(role_user("administrator"))
    archive = SimpleUploadedFile(
        "a.zip", MALFORMED[shape](exported), content_type="application/zip"
    )
    page = client.post("/import/", {"archive": archive})
    assert page.status_code == 200 and "Nothing was imported" in page.content.decode()
    assert not TestEvent.objects.exists()


JSON = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=20),
    lambda inner: (
        st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=5), inner, max_size=3)
    ),
    max_leaves=6,
)


@settings(
    max_examples=60,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(data=st.data())
def test_fuzzed_archive_structure_never_gives_a_server_error(exported, post, data):
    members = dict(exported)
    tables = sorted(n for n in members if n.startswith("data/") and members[n].strip())
    shape = data.draw(st.sampled_from(["field", "record", "manifest", "member"]))
    manifest = None
    if shape == "manifest":
        manifest = {data.draw(st.sampled_from(["members", "version", "format"])): data.draw(JSON)}
    elif shape == "member":
        name = data.draw(st.sampled_from(sorted(members)))
        members[name] = json.dumps(data.draw(JSON)).encode()
    else:
        name = data.draw(st.sampled_from(tables))
        lines = members[name].splitlines()
        index = data.draw(st.integers(0, len(lines) - 1))
        record = json.loads(lines[index])
        if shape == "field":
            record[data.draw(st.sampled_from(sorted(record)))] = data.draw(JSON)
        else:
            record = data.draw(JSON)
        lines[index] = json.dumps(record).encode()
        members[name] = b"\n".join(lines) + b"\n"
    response = post(signed_archive(members, manifest))
    assert response.status_code in (202, 400, 409), response.content


def _patched_directory(data: bytes, member: str, *, flags: int = 0, method: int | None = None):
    """The zip with ``member``'s central directory entry given more flag bits or
    another compression method (what an encrypting or AES zip tool writes)."""
    out = bytearray(data)
    at = out.find(b"PK\x01\x02")
    while at != -1:
        name_length = struct.unpack_from("<H", out, at + 28)[0]
        if out[at + 46 : at + 46 + name_length] == member.encode():
            old_flags = struct.unpack_from("<H", out, at + 8)[0]
            struct.pack_into("<H", out, at + 8, old_flags | flags)
            if method is not None:
                struct.pack_into("<H", out, at + 10, method)
            return bytes(out)
        at = out.find(b"PK\x01\x02", at + 4)
    raise LookupError(member)


@pytest.mark.parametrize(
    "change, message",
    [
        ({"method": 99}, "uses compression method 99"),
        ({"flags": 0x1}, "is encrypted"),
    ],
    ids=["aes-method-99", "encryption-flag"],
)
def test_encrypted_or_unknown_compression_members_are_400(exported, post, change, message):
    member = next(name for name in exported if name.startswith("data/"))
    response = post(_patched_directory(signed_archive(exported), member, **change))
    assert response.status_code == 400, response.content
    assert message in response.json()["detail"]
    assert not any(snapshot().values())
