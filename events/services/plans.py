"""Writes of a test plan that happen during a test: a person's judgement of a criterion."""

from django.core.exceptions import ValidationError
from django.db import transaction
from django.utils.translation import gettext

from events.models import Criterion, Judgement, Leg
from events.services.finality import require_amendable


@transaction.atomic
def judge(criterion: Criterion, *, passed: bool, leg: Leg | None = None, note: str = "", by=None):
    """Record (or change) the verdict on a criterion a person decides, for one of
    the case's legs or, without a leg, for the whole case."""
    if criterion.kind != Criterion.Kind.JUDGED:
        raise ValidationError(
            {
                "criterion": [
                    gettext(
                        "Only criteria judged by a person take a judgement; the others are "
                        "measured."
                    )
                ]
            }
        )
    if leg is not None and leg.test_case_id != criterion.test_case_id:
        raise ValidationError(
            {"leg": [(gettext("Leg %(leg)s does not drive this test case.") % {"leg": leg.number})]}
        )
    require_amendable(pk=criterion.test_case.test_event_id)
    judgement, _ = Judgement.objects.update_or_create(
        criterion=criterion, leg=leg, defaults={"passed": passed, "note": note, "by": by}
    )
    return judgement
