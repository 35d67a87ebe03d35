"""Analytic pixel models: C(V), conversion gain, photocurrent, discharge, dark current, noise."""
