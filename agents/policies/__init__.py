"""Policies: the :class:`~.protocol.Policy` protocol (SB3's ``predict``) and every controller that is not
trained here - v0's baselines (:mod:`.v0`), v1's field baselines (:mod:`.field`), the perfect-model
:mod:`.oracle`, all of them by name (:mod:`.factory`) - and the wrappers around trained models
(:mod:`.residual`, :mod:`.ensemble`). Imports numpy and srenv only."""
