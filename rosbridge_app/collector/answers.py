"""The collector's answers to a command (from the GUI or a ROS service), in
FTT_LANGUAGE: an operator reads them in the GUI's collector panel or the shell."""

from django.utils.translation import gettext, gettext_noop

# Starting (True) or stopping (False) logging.
LOGGING = {
    True: {
        "already": gettext_noop("Logging was already started; %(status)s."),
        "failed": gettext_noop("Could not start logging: %(exc)s"),
        "done": gettext_noop("Logging started; %(status)s."),
    },
    False: {
        "already": gettext_noop("Logging was already stopped; %(status)s."),
        "failed": gettext_noop("Could not stop logging: %(exc)s"),
        "done": gettext_noop("Logging stopped; the open segment is closed."),
        "spooled": gettext_noop(
            "Logging stopped; the open segment is closed as soon as the database is "
            "back (the request is spooled)."
        ),
    },
}


def logging_answer(on: bool, step: str, **values) -> str:
    return gettext(LOGGING[on][step]) % values
