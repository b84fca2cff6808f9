"""Django admin: the configuration UI for test administrators.

Configuration and catalogues are edited here.  The log hierarchy is browsable
with links up and down; its state changes (close, re-open) are admin actions
that call the service layer, and robot-recorded data is read-only.  Each
module registers the pages of one part; importing them here is what Django's
admin autodiscovery runs.
"""

from events.admin import accounts, configuration, logbook, plans

__all__ = ["accounts", "configuration", "logbook", "plans"]
