"""Tests of scenarios/run/ (tests/layout_rules.py)."""
