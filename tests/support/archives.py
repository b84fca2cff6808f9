"""FTT archives with chosen members, signed so only the content under test is wrong."""

import hashlib
import io
import json
import zipfile


def members_of(data: bytes) -> dict[str, bytes]:
    with zipfile.ZipFile(io.BytesIO(data)) as z:
        return {name: z.read(name) for name in z.namelist() if name != "manifest.json"}


def signed_archive(members: dict[str, bytes], manifest: dict | None = None) -> bytes:
    """A zip whose manifest lists every member with its true checksum and size;
    ``manifest`` replaces or adds top-level manifest fields."""
    listed = {
        name: {"sha256": hashlib.sha256(body).hexdigest(), "size": len(body)}
        for name, body in members.items()
    }
    head = {"format": "ftt-archive", "version": 1, "members": listed, **(manifest or {})}
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as z:
        for name, body in members.items():
            z.writestr(name, body)
        z.writestr("manifest.json", json.dumps(head))
    return out.getvalue()


def replace_record(members: dict[str, bytes], table: str, change) -> dict[str, bytes]:
    """``members`` with every record of ``table`` passed through ``change(record)``."""
    name = f"data/{table}.jsonl"
    records = [json.loads(line) for line in members[name].splitlines()]
    body = "".join(json.dumps(change(r)) + "\n" for r in records).encode()
    return {**members, name: body}
