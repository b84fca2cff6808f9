"""Login accounts with one of the roles."""

from django.contrib.auth.models import Group, User


def staff_user(role):
    """A user with ``role`` who may open Django admin."""
    user = User.objects.create_user(
        f"{role}-staff", password="pw-not-used-elsewhere", is_staff=True
    )
    user.groups.add(Group.objects.get(name=role))
    return user
