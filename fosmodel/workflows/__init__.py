"""Workflows: the steps below (noise, study, loop) put together over a whole record."""
