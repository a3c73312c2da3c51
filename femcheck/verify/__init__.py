"""``femcheck verify``: the analytical chain models across the test-point cube, compared with each
other (simplified vs detailed, rigid vs released joints) and with finite elements where available."""
