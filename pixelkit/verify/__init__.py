"""Sign-off: specs (``[spec]``), PVT corners, Monte Carlo yield, power, the sign-off table.

``pixelkit verify DESIGN`` measures every figure a spec names at every condition of the
design's ``[verify]`` grid (process corner x temperature x supply), and with ``mc`` > 0
at N Monte Carlo draws of the devices, then prints the table: spec, limit, worst
condition, value, margin, pass / fail, yield with its interval. See docs/verify.md.
"""
