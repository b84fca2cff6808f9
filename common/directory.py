"""The FTT role of a person who signs in from the directory (LDAP, Active Directory).

``settings.FTT_LDAP_ROLE_GROUPS`` maps roles to directory groups. At every
directory sign-in the account gets the highest role whose group holds the
person, and loses the other people's roles, so a change in the directory
takes effect at the next sign-in. A robot's role is never given this way.
"""

from django.conf import settings
from django.contrib.auth.models import Group

from common import roles


def directory_role(group_dns) -> str | None:
    """The highest role mapped to one of ``group_dns``, or None."""
    held = {dn.lower() for dn in group_dns}
    mapped = settings.FTT_LDAP_ROLE_GROUPS
    for role in reversed(roles.ORDER):
        if mapped.get(role, "").lower() in held:
            return role
    return None


def apply_directory_role(sender, user, ldap_user, **kwargs) -> None:
    """django-auth-ldap's ``populate_user``: runs before the account is saved."""
    role = directory_role(ldap_user.group_dns)
    if user.pk is None:
        user.save()
    people = Group.objects.filter(name__in=roles.ORDER)
    user.groups.remove(*people.exclude(name=role))
    if role is not None:
        user.groups.add(people.get(name=role))
