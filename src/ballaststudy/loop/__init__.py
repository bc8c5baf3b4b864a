"""Closing the loop with measured data: residuals, long-term accumulation, effects (issue 14)."""
