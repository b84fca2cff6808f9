from django.apps import AppConfig


class EventsConfig(AppConfig):
    name = "events"
    verbose_name = "Test events"

    def ready(self):
        from events import checks  # noqa: F401  (registers system checks)
