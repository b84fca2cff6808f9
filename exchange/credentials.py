"""An installation's sign-ins, kept across the restore of a backup without them.

A backup for the administrator role carries no password hash or token
(exchange.backup), so the accounts it restores cannot sign in. The machine's
owner saves the target's sign-ins before the restore and puts them back after
it (docs/data-exchange.md, "Restore"): every account keeps its password hash,
its API token, its people's role and its staff flags; an account the backup
does not hold is made again. The file signs everyone in, so it is written 0600.
"""

import json
import os
from pathlib import Path

from django.contrib.auth import get_user_model
from django.contrib.auth.models import Group
from django.db import transaction
from rest_framework.authtoken.models import Token

FORMAT = "ftt-credentials"
FLAGS = ("is_active", "is_staff", "is_superuser")


def save_credentials(path: Path) -> int:
    """Write every account's sign-in to ``path``; returns how many accounts."""
    tokens = dict(Token.objects.values_list("user_id", "key"))
    accounts = [
        {
            "username": user.get_username(),
            "password": user.password,
            "token": tokens.get(user.pk),
            "groups": sorted(user.groups.values_list("name", flat=True)),
            **{flag: getattr(user, flag) for flag in FLAGS},
        }
        for user in get_user_model().objects.order_by("pk").prefetch_related("groups")
    ]
    descriptor = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(descriptor, "w") as out:
        json.dump({"format": FORMAT, "accounts": accounts}, out)
    return len(accounts)


@transaction.atomic
def restore_credentials(path: Path) -> dict[str, int]:
    """Give the accounts in ``path`` their sign-ins back; returns what was done."""
    saved = json.loads(Path(path).read_text())
    if saved.get("format") != FORMAT:
        raise ValueError(f"{path} is not a file of ftt_credentials save.")
    users = get_user_model()
    groups = {group.name: group for group in Group.objects.all()}
    done = {"kept": 0, "made": 0}
    for account in saved["accounts"]:
        user, made = users.objects.get_or_create(username=account["username"])
        done["made" if made else "kept"] += 1
        user.password = account["password"]
        for flag in FLAGS:
            setattr(user, flag, account[flag])
        user.save()
        user.groups.add(*(groups[name] for name in account["groups"] if name in groups))
        if account["token"]:
            Token.objects.filter(user=user).exclude(key=account["token"]).delete()
            Token.objects.filter(key=account["token"]).exclude(user=user).delete()
            Token.objects.get_or_create(key=account["token"], defaults={"user": user})
    return done
