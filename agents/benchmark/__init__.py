"""The v1 benchmark (``python -m agents benchmark CONFIG``): its YAML (:mod:`.config`), the stages - tune,
train, distil, test - (:mod:`.stages`, :mod:`.runs`), the run that chains them (:mod:`.run`), the report
(:mod:`.report`) and its figure (:mod:`.figure`)."""
