"""Test-only support code: independent reference models the project is checked against."""
