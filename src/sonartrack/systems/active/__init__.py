"""The active sonar system: pings of a towed source received on a towed line array in, target tracks out
(papers P1 and P4).

Modules: records.py (the ping table and the navigation as typed records), scene_files.py (the scene's files:
the layout, the ping and table writers, and the checked readers); the chain's stages beside them (contacts,
detection across pings, tracking, outputs). Nothing is imported here: import from the modules.
"""
