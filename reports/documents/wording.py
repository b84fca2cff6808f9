"""The fixed words of the report's typst template (reports/templates_typst/report.typ
reads them as ``d.text``), in the language active while the report is built."""

from django.utils.translation import get_language
from django.utils.translation import gettext as _


def report_text() -> dict[str, str]:
    return {
        # typst hyphenates and quotes by it.
        "lang": (get_language() or "en")[:2],
        "provisional_mark": _("PROVISIONAL"),
        "field_test_report": _("Field Test Report"),
        "version": _("Version"),
        "provisional_title": _("PROVISIONAL: the test event has open segments"),
        "prepared_for": _("Prepared for"),
        "prepared_by": _("Prepared by"),
        "date": _("Date:"),
        "generated": _("generated"),
        "test_event": _("Test event"),
        "global_statistics": _("Global statistics"),
        "whole_test_event": _("Whole test event"),
        "distance_log": _("Distance log per shift"),
        "shift": _("Shift"),
        "vehicle": _("Vehicle"),
        "weather": _("Weather"),
        "distance": _("Distance"),
        "autonomous": _("Autonomous"),
        "auto_dist": _("Auto % (dist.)"),
        "auto_time": _("Auto % (time)"),
        "mean_auto_run": _("Mean auto run"),
        "max_auto_run": _("Max auto run"),
        "reliability": _("Interventions and reliability per shift"),
        "reliability_intro": _(
            "MDBI: mean distance between interventions, MTBI: mean time between "
            "interventions, with %(confidence)s confidence bounds."
        ),
        "interv": _("Interv."),
        "per_km": _("per km"),
        "per_hour": _("per hour"),
        "per_vehicle": _("Per vehicle"),
        "reasons_heading": _("Reasons: interventions and manual time"),
        "reason": _("Reason"),
        "counts_as_intervention": _("Counts as intervention"),
        "interventions": _("Interventions"),
        "manual_time": _("Manual time"),
        "overview_map": _("Overview map"),
        "shift_summary": _("Shift summary"),
        "mode_statistics": _("Auto/ITO statistics"),
        "mode": _("Mode"),
        "runs": _("Runs"),
        "time": _("Time"),
        "speed_ms": _("Speed (m/s)"),
        "speed_kmh": _("Speed (km/h)"),
        "no_segments": _("No segments in this shift."),
        "timeline": _("Timeline"),
        "segments": _("Segments"),
        "ito_segments": _("Interventions (ITO segments)"),
        "open_segment": _("Open segment: its figures are provisional."),
        "notes": _("Notes"),
        "camera_images": _("Camera images"),
        "back_to_segment": _("back to the segment"),
        "methods": _("Methods and data quality"),
        "counted_interventions": _("Counted interventions"),
        "counted_intro": _(
            "An intervention is a manual (ITO) segment with at least one reason that counts "
            "as an intervention. A segment with several counted reasons is counted once "
            "overall and once under each of its reasons."
        ),
        "counted": _("Counted:"),
        "not_counted": _("Not counted:"),
        "none": _("none"),
        "formulas": _("Formulas"),
        "data_gaps": _("Data gaps"),
        "without_poses": _(
            "Segments without positions (their distance is only the straight join between "
            "start positions, where known):"
        ),
        "gaps": _("Gaps of more than %(seconds)s s between consecutive positions:"),
        "gaps_more": _("and %(count)s more."),
        "no_fix": _("Positions without a GPS fix (left out):"),
        "no_start": _("Segments without a start position:"),
        "unknown_mode": _(
            "Logged before the robot said its mode (unknown mode; in the totals, not in "
            "autonomy or intervention figures):"
        ),
        "presentation": _("Presentation"),
        "times_in": _(
            "All times are in the test event's time zone, %(zone)s. Positions: %(mode)s."
        ),
        "fonts": _("Fonts:"),
        "warnings": _("Warnings while building this report:"),
        "fixes_missed": _(
            "GPS fixes lost on the way to the collector (its estimate from gaps in the "
            "robot’s stamps):"
        ),
        "uncertain_starts": _(
            "Segments whose start is uncertain (the robot’s mode message had no time stamp; "
            "the switch lies up to the given time before the stored start):"
        ),
        "at_most": _(", at most %(seconds)s s"),
        "footer_provisional": _("provisional – open segments"),
        "final_since": _("final since"),
        "footer_zone": _("times in %(zone)s"),
        "final_title": _("FINAL since %(when)s"),
        "test_plan": _("Test plan"),
        "test_plan_intro": _(
            "Each test case’s criteria, judged on the figures above (same rules): pass, fail, "
            "not yet (still being driven) or needs a judgement (decided by a person)."
        ),
        "test_case": _("Test case"),
        "scope": _("Scope"),
        "criterion": _("Criterion"),
        "measured": _("Measured"),
        "verdict": _("Verdict"),
        "unplanned": _("Legs outside the plan:"),
        "provenance": _("Provenance"),
        "data_digest": _("Data digest (SHA-256)"),
        "built": _("Built"),
        "taxonomy": _("Taxonomy"),
        "ftt_version": _("FTT version"),
        "status": _("Status"),
        "status_provisional": _("provisional (open segments)"),
        "not_finalised": _("not finalised"),
        "check_with": _("Check with:"),
        # A command, the same in every language.
        "verify_command": "manage.py ftt_report --verify REPORT.pdf",
        "report_options": _("Report options:"),
        "amendments": _("Amendments after finalisation:"),
    }


def shift_name(number: int) -> str:
    return _("Shift %(number)s") % {"number": number}


def comparison_text() -> dict[str, str]:
    """The fixed words of reports/templates_typst/compare.typ (``d.text``)."""
    return {
        "lang": (get_language() or "en")[:2],
        "title": _("Reliability across test events"),
        "interv": _("Interv."),
        "auto_distance": _("Auto distance"),
        "per_km": _("per km"),
        "per_hour": _("per hour"),
        "per_test_event": _("Per test event"),
        "test_event": _("Test event"),
        "per_version": _("Per software version"),
        "version": _("Version"),
        "per_vehicle": _("Per vehicle"),
        "vehicle": _("Vehicle"),
        "growth": _("Reliability growth"),
        "no_fit": _("Fewer than two interventions: no growth fit."),
        "hotspots": _("Take-over hotspots"),
        "no_hotspot": _("No take-over with a position."),
        "hotspot": _("Hotspot"),
        "take_overs": _("Take-overs"),
        "reasons": _("Reasons"),
        "hotspot_segments": _("Segments (test event: segment)"),
        "methods": _("Methods"),
        "generated": _("generated"),
        "routes": _("Routes"),
        "route": _("Route"),
        "colour": _("Colour"),
        "driven_or_planned": _("Driven or planned"),
        "deviation_note": _(
            "Deviation: the distance of each point of one route from the other route's line; "
            "in red where it is more than %(threshold)s. Fréchet: the discrete Fréchet distance "
            "of the pair."
        ),
        "deviation": _("Deviation"),
        "frechet": _("Fréchet"),
        "mean": _("Mean"),
        "p95": _("95th percentile"),
        "maximum": _("Maximum"),
        "beyond_threshold": _("Beyond threshold"),
    }
