"""Kabir et al. setup planning: reach test and n_rfc (``reach``), uniform / hierarchical /
random sampling with gradient descent (``sampling``), dominance (``dominance``) and
:func:`mavac.setups.setup_plan.plan_setups`. The set-cover search itself is generic and lives in
:mod:`mavac.planning.setcover`; the two-arm cell's feasibility test, which plugs into
``plan_setups(feasible=...)``, in :mod:`mavac.scrubbing.holding`."""
