"""Which accounts the directory may sign in: those it made, marked as its own."""

import pytest
from django.contrib.auth.models import Group, User
from django.db import connection
from django.db.migrations.executor import MigrationExecutor

from common import roles
from common.directory import is_local_name
from common.models import DirectoryAccount


@pytest.mark.django_db(transaction=True)
def test_the_upgrade_marks_only_the_accounts_the_directory_made():
    executor = MigrationExecutor(connection)
    executor.migrate([("common", "0002_account_preference_and_labels")])
    # As django-auth-ldap made them: no local password, a person's role.
    made = User.objects.create_user("vera")
    made.groups.add(Group.objects.get(name=roles.VIEWER))
    User.objects.create_user("lena", password="lena-local-pw-1")
    robot = User.objects.create_user("robot-a")
    robot.groups.add(Group.objects.get(name=roles.ROBOT))
    superuser = User.objects.create_superuser("root")
    superuser.set_unusable_password()
    superuser.save()
    executor.loader.build_graph()
    executor.migrate(executor.loader.graph.leaf_nodes())
    assert list(DirectoryAccount.objects.values_list("user__username", flat=True)) == ["vera"]
    assert not is_local_name("Vera")
    assert all(is_local_name(name) for name in ("lena", "ROBOT-A", "root"))
