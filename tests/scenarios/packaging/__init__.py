"""Tests of scenarios/packaging/ (tests/layout_rules.py)."""
