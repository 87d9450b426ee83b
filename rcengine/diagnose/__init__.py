"""Mismatch diagnosis: locate where model and recordings differ, name the missing physics, add it,
refit, and show the fit improve on a later period.

    report = diagnose(frame, building, model="basic")
    report.to_json()   # CONTRACT.md §3 diagnose report

``settings`` (what is asked), ``selection`` (the forward selection), ``locate``, ``candidates``,
``screen``, ``fitting``, ``report`` and ``html`` (its steps and outputs).
"""

from rcengine.diagnose.report import Report
from rcengine.diagnose.selection import diagnose
from rcengine.diagnose.settings import DiagnoseSettings, split_time

__all__ = ["DiagnoseSettings", "Report", "diagnose", "split_time"]
