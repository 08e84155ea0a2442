"""Presentation: the command line, its plots, the HTML report, the 3-D view and JSON output.

The top layer: it imports the application (``mrclutch.design``, ``pipeline``, ``sweep``,
…) and nothing imports it. ``mrclutch.cli.main:main`` is the console entry point.
"""
