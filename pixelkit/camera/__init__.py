"""The designed pixel as a virtual camera: noise, response, photon transfer, EMVA 1288 figures and data."""
