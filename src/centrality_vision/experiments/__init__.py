"""The thesis' experiments, one module each, printing our numbers beside the thesis'.

- :mod:`centrality_vision.experiments.table_4_1`: shape classification on Kimia-99 under
  salt noise (Table 4.1, fig. 4.8).
"""

__all__ = ["table_4_1"]
