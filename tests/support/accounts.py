"""Login accounts with one of the roles."""

from django.contrib.auth.hashers import PBKDF2PasswordHasher
from django.contrib.auth.models import Group, User


class QuickPBKDF2PasswordHasher(PBKDF2PasswordHasher):
    """PBKDF2-SHA256 at a thousand rounds: a hash every FTT process checks (the
    rounds are part of the hash), made in a millisecond."""

    iterations = 1_000


def staff_user(role):
    """A user with ``role`` who may open Django admin."""
    user = User.objects.create_user(
        f"{role}-staff", password="pw-not-used-elsewhere", is_staff=True
    )
    user.groups.add(Group.objects.get(name=role))
    return user


def signed_in(client, name: str, role: str):
    """A user with ``role``, signed in on the test ``client``."""
    user = User.objects.create_user(name, password="pw")
    user.groups.add(Group.objects.get(name=role))
    client.force_login(user)
    return user
