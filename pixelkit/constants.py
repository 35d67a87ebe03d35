"""Physical constants (SI, CODATA 2018 exact values where defined)."""
Q = 1.602176634e-19      # elementary charge, C
K_B = 1.380649e-23       # Boltzmann constant, J/K
H = 6.62607015e-34       # Planck constant, J s
C0 = 299792458.0         # speed of light, m/s
T0 = 273.15              # 0 degC in K
KM = 683.002             # maximum luminous efficacy, lm/W (photopic, 555 nm)
