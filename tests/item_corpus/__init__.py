"""Small scripts in the style of Exudyn's TestModels, one item each (issue 16's items):
every module builds its model in ``Build()`` -> (mbs, simulationSettings) with the script's own
step, and solves it with ``exl.SolveDynamic`` when run as a script.  tests/test_item_corpus.py
checks each against Exudyn's generalized-alpha at a fine step."""
