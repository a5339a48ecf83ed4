"""Scenarios generated at any size: floor plans, placement of starts and tasks, and
the files ``mrcomm scenario make`` writes."""
