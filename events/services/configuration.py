"""Writes to configuration rows (personnel, performers, vehicles, pose sources)
and to the seeded catalogues."""

from django.db import transaction
from django.db.models import Model
from django.utils.translation import gettext as _

from common.errors import RuleViolation
from events.models import ItoReason, SegmentType
from events.services import deletion

# The state machine refers to these keys by name; without them it cannot log.
_KEYS_IN_CODE = {
    ItoReason: {ItoReason.UNASSIGNED},
    SegmentType: {SegmentType.ITO, SegmentType.AUTO, SegmentType.UNKNOWN},
}


@transaction.atomic
def create_configuration(model: type[Model], **fields) -> Model:
    instance = model(**fields)
    instance.full_clean()
    instance.save()
    return instance


@transaction.atomic
def update_configuration(instance: Model, **fields) -> Model:
    instance = type(instance).objects.select_for_update().get(pk=instance.pk)
    if instance._meta.pk.name in fields and fields[instance._meta.pk.name] != instance.pk:
        # Saving a changed primary key would copy the row, not rename it.
        raise RuleViolation({instance._meta.pk.name: [_("A catalogue key cannot be changed.")]})
    for name, value in fields.items():
        setattr(instance, name, value)
    instance.full_clean()
    instance.save()
    return instance


def is_used_by_rules(instance: Model) -> bool:
    return instance.pk in _KEYS_IN_CODE.get(type(instance), ())


@transaction.atomic
def delete_configuration(instance: Model) -> None:
    if is_used_by_rules(instance):
        raise RuleViolation(
            _("'%(key)s' is used by the logging rules themselves and cannot be deleted.")
            % {"key": instance.pk}
        )
    deletion.delete(instance)
