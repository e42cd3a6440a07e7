"""Tests of controller/ (tests/layout_rules.py)."""
