"""Login accounts with one of the roles."""

from django.contrib.auth.models import Group, User


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
