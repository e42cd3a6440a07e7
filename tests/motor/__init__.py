"""Tests of motor/ (tests/layout_rules.py)."""
