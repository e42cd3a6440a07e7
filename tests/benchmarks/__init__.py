"""Tests of benchmarks/ (tests/layout_rules.py)."""
