"""The deaf watch: a collector whose side of DDS has gone deaf.

While logging, nothing heard for ``params.deaf_timeout`` seconds although other
nodes publish sensor topics the collector subscribes to means its side of DDS
is deaf (seen after a SIGKILL restart): the subscriptions are re-created, and
if that does not help within another timeout, the collector renews itself.
"""

import logging

from django.utils.translation import gettext, gettext_noop

log = logging.getLogger("ftt.collector")

# Inputs a robot publishes all the time while it runs; the mode and maps may
# come only on a change, so their silence says nothing about the collector.
STREAMS = ("gps_fix", "tf", "local_pose", "image", "image_compressed")
DEAF = gettext_noop("robot publishes, collector hears nothing")

RESUBSCRIBE = "resubscribe"
RENEW = "renew"


class DeafWatch:
    """Decides, once a tick, what a deaf collector does; ``text`` is empty or
    what the GUI shows while the collector hears nothing."""

    def __init__(self, t: float):
        self.text = ""
        self._heard = (0, t)
        self._steps = 0

    def check(self, t: float, received: int, timeout: float, logging_on: bool, publishing):
        """RESUBSCRIBE, RENEW or None, at monotonic time ``t`` with ``received``
        messages counted over all inputs so far; ``publishing()`` lists the
        stream topics other nodes publish (asked only when it matters)."""
        count, since = self._heard
        if received != count or not timeout or not logging_on:
            if self.text and received != count:
                log.warning(gettext("the collector hears its topics again"))
            self._heard = (received, t)
            self.text, self._steps = "", 0
            return None
        if t - since < timeout:
            return None
        self._heard = (received, t)
        topics = publishing()
        if not topics:  # the robot is quiet: nothing to hear
            self.text, self._steps = "", 0
            return None
        self._steps += 1
        names = ", ".join(topics)
        if self._steps == 1:
            self.text = gettext(
                "%(deaf)s (%(topics)s) for %(seconds)s s: subscriptions re-created"
            ) % {
                "deaf": gettext(DEAF),
                "topics": names,
                "seconds": f"{timeout:g}",
            }
            log.warning("%s", self.text)
            return RESUBSCRIBE
        self.text = gettext("%(deaf)s (%(topics)s) for %(seconds)s s: the collector restarts") % {
            "deaf": gettext(DEAF),
            "topics": names,
            "seconds": f"{timeout * 2:g}",
        }
        log.warning("%s", self.text)
        self._steps = 0  # if it stays, re-created subscriptions come first again
        return RENEW
