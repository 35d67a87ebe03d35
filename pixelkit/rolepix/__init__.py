"""Measurements of a pixel read by role with true CDS: any :class:`~pixelkit.circuits.roles.PixelCell`
(the 4T generator's, or a designer's netlist), the same decks and figures for both.

- ``run``: decks through the engine, with a Monte Carlo draw of the devices;
- ``signal``: conversion gain, full well, image lag (the ladder and the lag decks);
- ``noise``: the read noise of the true-CDS read (.noise), and its transient-noise check;
- ``dark``, ``prnu``, ``power``: the other figures of ``verify.figures.ROLE_FIGURES``;
- ``suite``: what ``pixelkit verify`` runs for these designs (groups, figures, conditions).

A design here is a ``families.roledesign.RoleDesign``; its ``cell()`` gives the pixel.
"""
