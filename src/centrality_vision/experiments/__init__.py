"""The thesis' experiments, one module each, printing our numbers beside the thesis'.

Each module has ``run(quick=..., seed=...) -> dict``, ``format_table(result) -> str`` and
``main(argv) -> int`` (``python -m centrality_vision.experiments.<module>`` or
``centrality-vision reproduce <name>``); :data:`EXPERIMENTS` maps the command-line names to
the modules. Long experiments run their independent units through
:mod:`centrality_vision.experiments._runner` (resumable; local processes or Dask).

- ``table-2.1`` (:mod:`.table_2_1`): the four centralities of the 6-node graph.
- ``table-4.1`` (:mod:`.table_4_1`): shape classification on Kimia-99 under salt noise
  (Table 4.1, fig. 4.8).
- ``fig-5.3`` (:mod:`.fig_5_3`): the fish under a similarity transform, CPD against GPD with
  four centralities (figs. 5.3, 5.4).
- ``fig-5.5`` (:mod:`.fig_5_5`): the 3D face, affine with missing points (figs. 5.5, 5.6).
- ``fig-5.7`` (:mod:`.fig_5_7`): the fish, non-rigid with outliers and missing points (figs. 5.7, 5.8).
- ``table-5.1`` (:mod:`.table_5_1`): 495 point sets of five classes (Tables 5.1-5.3).
- ``fig-6.4`` (:mod:`.fig_6_4`): MWME matching of Kimia-99 outlines under similarity
  transforms and noise.
- ``fig-7.1`` (:mod:`.fig_7_1`): MST against MSTME on five points, with an exhaustive check.
- ``fig-7.4`` (:mod:`.fig_7_4`): stability of MSTME, Delaunay, Gabriel and EMST graphs under
  perturbation (figs. 7.3-7.5).
"""

EXPERIMENTS = {
    "table-2.1": "table_2_1",
    "table-4.1": "table_4_1",
    "fig-5.3": "fig_5_3",
    "fig-5.5": "fig_5_5",
    "fig-5.7": "fig_5_7",
    "table-5.1": "table_5_1",
    "fig-6.1": "fig_6_1",
    "fig-6.4": "fig_6_4",
    "fig-7.1": "fig_7_1",
    "fig-7.4": "fig_7_4",
}

__all__ = ["EXPERIMENTS"]
