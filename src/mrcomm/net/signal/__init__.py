"""Signal-strength models (SSD/ESD): path-loss theory, calibration CSVs, SVR
models and their JSON form, the fast RSSI lookup table, ``iw`` parsing and RSSI traces.

Import the submodules directly (``mrcomm.net.signal.table`` ...): this package imports
nothing itself so that the hot path never pays for scikit-learn or matplotlib.
"""
