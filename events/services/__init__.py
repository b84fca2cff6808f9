"""Every write to the log hierarchy goes through these functions.

The REST API, the GUI, admin actions, the collector and the importers call
them; none of those re-implement a rule.
"""
