"""Writers for run outputs: time series (CSV), particle snapshots (VTU + PVD), summary (JSON).

Every file is written atomically (to a temporary file in the same folder, then renamed),
so a run that is killed never leaves a half-written output behind.
"""
