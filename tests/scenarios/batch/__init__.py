"""Tests of scenarios/batch/ (tests/layout_rules.py)."""
