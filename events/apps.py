from django.apps import AppConfig
from django.db.models.signals import m2m_changed, post_delete, post_save
from django.utils.translation import gettext_lazy as _


class EventsConfig(AppConfig):
    name = "events"
    verbose_name = _("Test events")

    def ready(self):
        from django.contrib.auth import get_user_model
        from simple_history.signals import pre_create_historical_record

        from events import checks  # noqa: F401  (registers system checks)
        from events.history import stamp_origin
        from events.models import Leg, RobotAccount, Segment, Vehicle
        from events.selectors.robots import forget_bindings
        from events.selectors.segments import forget_pose_targets

        # What a robot may write into, cached per process for a few seconds.
        for sender in (RobotAccount, Vehicle, get_user_model()):
            post_save.connect(forget_bindings, sender=sender, weak=False)
            post_delete.connect(forget_bindings, sender=sender, weak=False)
        m2m_changed.connect(forget_bindings, sender=RobotAccount.vehicles.through, weak=False)
        # A pose's target carries its leg (the leg's default pose source).
        for sender in (Segment, Leg):
            post_save.connect(forget_pose_targets, sender=sender, weak=False)
            post_delete.connect(forget_pose_targets, sender=sender, weak=False)
        pre_create_historical_record.connect(stamp_origin, weak=False)
