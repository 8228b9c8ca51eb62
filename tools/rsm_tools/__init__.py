"""Host-side tools for the rsm scan-matching library.

Modules:

* :mod:`rsm_tools.carmen`   -- streaming CARMEN log reader and writer
* :mod:`rsm_tools.evaluate` -- relative-pose error (``rsm-evaluate``)
* :mod:`rsm_tools.outliers` -- deterministic outlier injection (``rsm-outliers``)
* :mod:`rsm_tools.excerpt`  -- cut a log and its ground truth (``rsm-excerpt``)
"""

__version__ = "0.1.0"
