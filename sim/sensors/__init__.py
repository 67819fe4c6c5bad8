"""Sensor suites: from the truth record to the measured record."""
