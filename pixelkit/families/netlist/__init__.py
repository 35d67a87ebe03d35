"""A pixel from the designer's own SPICE netlist (family ``netlist``): docs/pixel-netlist.md."""
