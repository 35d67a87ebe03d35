"""The ratio-based HDR pixel (SEEDS_BRIEF section 5): a weak-inversion translinear
loop per photodiode pair, a PWM readout and a column counter."""
