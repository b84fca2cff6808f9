from django.apps import AppConfig


class FttSiteConfig(AppConfig):
    name = "ftt_site"

    def ready(self):
        from django.contrib.auth.signals import user_logged_in

        from ftt_site.inbound.lockout import forgive_own_failures

        user_logged_in.connect(forgive_own_failures, dispatch_uid="ftt-forgive-own-failures")
