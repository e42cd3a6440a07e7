"""Tests of scenarios/scenes/ (tests/layout_rules.py)."""
