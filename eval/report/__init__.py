"""Reporting: Table I and the other tables, figures, the run record."""
