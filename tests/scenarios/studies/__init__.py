"""Tests of scenarios/studies/ (tests/layout_rules.py)."""
