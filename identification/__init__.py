"""Identification methods; each returns an ``identification.estimate.Estimate``."""
