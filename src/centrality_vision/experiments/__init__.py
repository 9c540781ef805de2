"""The thesis' experiments, one module each, printing our numbers beside the thesis'.

- :mod:`centrality_vision.experiments.table_4_1`: shape classification on Kimia-99 under
  salt noise (Table 4.1, fig. 4.8).
- :mod:`centrality_vision.experiments.fig_5_3`: the fish under a similarity transform, CPD
  against GPD with four centralities (figs. 5.3, 5.4).
- :mod:`centrality_vision.experiments.fig_6_4`: MWME matching of Kimia-99 outlines under
  similarity transforms and noise.
- :mod:`centrality_vision.experiments.fig_7_4`: stability of MSTME, Delaunay, Gabriel and
  EMST graphs under perturbation (figs. 7.3-7.5).
"""

__all__ = ["table_4_1", "fig_5_3", "fig_6_4", "fig_7_4"]
