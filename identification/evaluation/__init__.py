"""Evaluation of estimates: scoring against truth, validation metrics, HTML reports."""
