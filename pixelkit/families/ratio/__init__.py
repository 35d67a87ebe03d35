"""The ratio-based HDR pixel [Sun2016]: a weak-inversion translinear
loop per photodiode pair, a PWM readout and a column counter."""
