"""EMVA 1288 datasets: strict reading, the standard's figures, and the camera-level gap.

Reading (``read_descriptor``, ``load_image``): the descriptor layout of the
emva1288 reference implementation (``v``, ``n bits width height``, ``b
exposure photons`` / ``d exposure`` each followed by ``i path`` lines: two
images per temporal step, more for a spatial stack). Exposure is in
nanoseconds, the reference's convention (its dark-current figures multiply the
slope by 1e9), unless a comment line states the unit (``# ... exposure in us``;
ns, us, ms or s). PNGs of any bit depth (8 - 16) are read as the integers they
hold (a 12-bit camera in 16-bit PNGs is *not* rescaled) and must fit the
stated bit depth. Image paths must stay inside the dataset folder. Every
problem (binary or non-UTF-8 descriptor, bad ``n``/``b``/``d``/``i`` line,
missing, truncated or mis-sized image, no dark steps) is one line naming the
file and what is wrong.

Figures (``figures``): computed as the reference implementation computes them
(``emva1288.process.results``): K and R by least squares through the origin
over 0 - 70 % of saturation (saturation = the variance maximum, found as the
reference scans for it), QE = R / K, temporal dark noise from the dark
variance (its intercept against exposure when there are more than two
exposures; floored at 0.24 DN^2), sigma_d, mu_p.min, saturation capacity,
SNR_max, DR, linearity error (weighted fit over 5 - 95 %), dark current from
the mean AND from the variance, DSNU and PRNU from the spatial stacks.

Camera-level gap (``analyse``). Nominal model (EMVA 1288 Linear): mu_y =
mu_y.dark(t) + R mu_p (the dark frames' line at the step's exposure t, as the
standard subtracts the dark of the same exposure), sigma_y^2 = sigma_y.dark^2 +
K (mu_y - mu_y.dark), each step's mean that of its pixels clipped at the ADC's full
scale (E[min(X, full scale)], X spread by that temporal noise). Where: residuals of the mean and of the variance by
fraction of saturation. Which: candidate camera-level augmentations, each
fitted on the even exposure steps and judged on the odd (held-out) ones, with the
statistics and verdict words of ``gap diagnose`` (``camera_verdict``): each step's
mean is known to its own noise (the pair's temporal variance over its pixels, and the
quantisation's), a candidate must beat the linear model on the held-out steps, and
"explained" means the held-out steps are then within that noise:

- ``nonlinearity``: response compression mu = mu_d + R mu_p (1 - b R mu_p)
  (the pixel-level ``sf_gain`` / C(V) signature);
- ``soft_saturation``: pixels do not all clip at once (a Gaussian spread of
  pixel responses clipped at full scale);
- ``dark_current``: the bright steps' level grows with exposure beyond the dark frames' (mu += D t).

And the dark noise: when the dark current from the variance and from the mean
disagree (ratio outside 1/1.5 .. 1.5, both positive and resolved), the answer
names ``non_poisson_dark_noise`` (e.g. RTS / hot-pixel tails, or a dark offset
drift that is not shot noise); a dark variance that grows while the dark mean
does not (or falls) is named the same way.
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares
from scipy.stats import norm

from ..errors import PixelkitError
from ..fileio import path_kind
from ..readfile import FileRefused, check_file, open_file, read_bytes

UNITS = {"ns": 1e-9, "us": 1e-6, "µs": 1e-6, "ms": 1e-3, "s": 1.0}
_UNIT_RE = re.compile(r"exposure[^\n]*?\bin\s+(ns|us|µs|ms|s)\b", re.I)
S2Q = 1.0 / 12.0


class EmvaError(PixelkitError):
    def __init__(self, where, what):
        super().__init__(f"{where}: {what}")


def _num(tok, line_no, path, what, integer=False):
    try:
        v = int(tok) if integer else float(tok)
    except ValueError:
        raise EmvaError(f"{path}:{line_no}", f"{what} '{tok}' is not a{'n integer' if integer else ' number'}") from None
    if integer and not 0 <= v <= 10 ** 9:
        raise EmvaError(f"{path}:{line_no}", f"{what} {tok[:20]} must be a whole number 0 .. 1e9")
    if not np.isfinite(v) or v < 0:
        raise EmvaError(f"{path}:{line_no}", f"{what} {tok[:20]} must be finite and >= 0")
    return v


def read_descriptor(folder: str | Path) -> dict:
    folder = Path(folder)
    path = folder / "EMVA1288_Data.txt" if path_kind(folder) == "dir" else folder
    try:
        raw = read_bytes(path, "descriptor", "descriptor")
    except FileRefused as exc:
        if exc.missing:
            raise EmvaError(str(path), "not found (an EMVA 1288 dataset is a folder with EMVA1288_Data.txt)") from None
        raise
    if b"\0" in raw:
        raise EmvaError(str(path), "binary file (NUL bytes), not an EMVA 1288 descriptor")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        raise EmvaError(str(path), f"not UTF-8 text (byte {e.start})") from None
    base = path.parent.resolve()
    steps, cur, fmt, unit = [], None, None, "ns"
    for k, line in enumerate(text.splitlines(), 1):
        f = line.split()
        if not f:
            continue
        if f[0].startswith("#"):
            m = _UNIT_RE.search(line)
            if m:
                unit = m.group(1).lower()
            continue
        if f[0] == "v":
            continue
        if f[0] == "n":
            if len(f) != 4:
                raise EmvaError(f"{path}:{k}", f"'{line.strip()}' should be 'n bits width height'")
            if fmt is not None:
                raise EmvaError(f"{path}:{k}", "a second 'n' line")
            bits, w, h = (_num(x, k, path, name, True) for x, name in zip(f[1:], ("bits", "width", "height")))
            if not 1 <= bits <= 16 or w < 1 or h < 1 or w * h > MAX_PIXELS:
                raise EmvaError(f"{path}:{k}", f"'{line.strip()}': bits must be 1..16, width and height >= 1, "
                                               f"width x height at most {MAX_PIXELS} pixels")
            fmt = {"bits": bits, "width": w, "height": h}
        elif f[0] in ("b", "d"):
            want = 3 if f[0] == "b" else 2
            if len(f) != want:
                form = "b exposure photons" if f[0] == "b" else "d exposure"
                raise EmvaError(f"{path}:{k}", f"'{line.strip()}' should be '{form}'")
            t = _num(f[1], k, path, "exposure")
            mu_p = _num(f[2], k, path, "photons") if f[0] == "b" else 0.0
            cur = {"kind": "d" if mu_p == 0.0 else "b", "t": t * UNITS[unit], "t_raw": t, "mu_p": mu_p,
                   "imgs": [], "line": k}
            steps.append(cur)
        elif f[0] == "i":
            if cur is None:
                raise EmvaError(f"{path}:{k}", "an 'i' line before any 'b' or 'd' line")
            if len(f) != 2:
                raise EmvaError(f"{path}:{k}", f"'{line.strip()}' should be 'i relative/path.png'")
            try:
                p = (base / Path(*f[1].replace("\\", "/").split("/"))).resolve()
            except (RuntimeError, OSError):   # Python 3.11 raises RuntimeError on a loop
                raise EmvaError(f"{path}:{k}", f"image '{f[1]}' is a loop of symbolic links") from None
            if not p.is_relative_to(base):
                raise EmvaError(f"{path}:{k}", f"image path '{f[1]}' leaves the dataset folder")
            try:
                check_file(p, "image", "image", limit=1 << 62)   # its size is checked when it is read
            except FileRefused as exc:
                why = "not found" if exc.missing else f"is {exc.value}, not a regular file"
                raise EmvaError(f"{path}:{k}", f"image '{f[1]}' {why}") from None
            cur["imgs"].append(p)
        else:
            raise EmvaError(f"{path}:{k}", f"unknown line '{line.strip()[:40]}' (allowed: v, n, b, d, i, #)")
    if fmt is None:
        raise EmvaError(str(path), "no 'n bits width height' line")
    for s_ in steps:
        if len(s_["imgs"]) < 2:
            raise EmvaError(f"{path}:{s_['line']}", "a step needs at least two images")
    temporal = [s_ for s_ in steps if len(s_["imgs"]) == 2]
    _check_order(path, steps, temporal)
    if not any(s_["kind"] == "d" for s_ in temporal):
        raise EmvaError(str(path), "no dark steps (a 'd' line, or 'b' with 0 photons, with two images)")
    if not any(s_["kind"] == "b" for s_ in temporal):
        raise EmvaError(str(path), "no bright steps with two images")
    return {"bits": fmt["bits"], "width": fmt["width"], "height": fmt["height"], "steps": steps,
            "source": str(path), "exposure_unit": unit}


def _check_order(path, steps, temporal) -> None:
    """Issue 44: a step listed twice (its data counted twice, the fit weighted by a copy), an image
    file used twice, and temporal steps out of order are refused. The descriptor lists the photon
    transfer series in increasing light: each bright step with more photons than the one before
    (at the same or a longer exposure), each dark step at the same or a longer exposure (the
    irradiance method repeats one exposure)."""
    if steps and all(s_["t"] == 0 for s_ in steps):
        raise EmvaError(str(path), "every exposure is 0: no photons can be collected (check the 'b' and 'd' lines)")
    seen, used = {}, {}
    for s_ in steps:
        key = (s_["kind"], s_["t"], s_["mu_p"], len(s_["imgs"]) == 2)
        # a bright temporal step twice (darks may repeat an exposure: the irradiance method; a spatial
        # stack may sit at a temporal step's light)
        if key in seen and s_["kind"] == "b" and len(s_["imgs"]) == 2:
            raise EmvaError(f"{path}:{s_['line']}", f"this step repeats the step of line {seen[key]} (same exposure "
                                                    "and photons): each step once")
        seen[key] = s_["line"]
        for img in s_["imgs"]:
            if img in used:
                raise EmvaError(f"{path}:{s_['line']}", f"image {img.name} is already used by the step of line "
                                                        f"{used[img]}: each image once")
            used[img] = s_["line"]
    for kind in ("b", "d"):
        series = [s_ for s_ in temporal if s_["kind"] == kind]
        for a, b in zip(series, series[1:]):
            if kind == "b" and not (b["mu_p"] > a["mu_p"] and b["t"] >= a["t"]):
                raise EmvaError(f"{path}:{b['line']}", f"photons {b['mu_p']:g} at exposure {b['t_raw']:g} after "
                                f"{a['mu_p']:g} at {a['t_raw']:g} (line {a['line']}): bright steps come in increasing "
                                "light - photon counts must grow with exposure, step by step")
            if kind == "d" and b["t"] < a["t"]:
                raise EmvaError(f"{path}:{b['line']}", f"dark exposure {b['t_raw']:g} after {a['t_raw']:g} "
                                f"(line {a['line']}): dark steps come in increasing exposure")


#: Largest image the kit decodes (a 268-megapixel sensor); the descriptor's size must not exceed it.
MAX_PIXELS = 1 << 28


def image_limit(desc: dict) -> int:
    """Largest file an image of the descriptor's size can be: raw bytes twice over plus 1 MiB of
    metadata (PNG stores incompressible data with a few bytes per 64 kB, and each row one filter byte)."""
    return 2 * desc["width"] * desc["height"] * (1 if desc["bits"] <= 8 else 2) + (1 << 20)


def load_image(p: Path, desc: dict) -> np.ndarray:
    """One image as the integers it holds; checked against the descriptor's size and bit depth,
    its file size and its stated dimensions checked before anything is decoded."""
    import warnings

    from PIL import Image, UnidentifiedImageError
    want = (desc["width"], desc["height"])
    try:
        with open_file(p, "image", "image", limit=image_limit(desc)) as fh, warnings.catch_warnings():
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)   # the size is checked below
            with Image.open(fh) as im:
                if im.size != want:
                    raise EmvaError(str(p), f"size {im.size[0]} x {im.size[1]} differs from the descriptor's "
                                            f"{want[0]} x {want[1]} (not decoded)")
                im.load()
                a = np.asarray(im)
    except FileRefused as exc:
        raise EmvaError(str(p), f"{exc.value}: expected {exc.allowed} (the descriptor states {want[0]} x "
                                f"{want[1]} at {desc['bits']} bits)") from None
    except Image.DecompressionBombError:
        raise EmvaError(str(p), f"states more pixels than Pillow decodes safely; the descriptor states "
                                f"{want[0]} x {want[1]} (not decoded)") from None
    except (UnidentifiedImageError, OSError, SyntaxError, ValueError) as e:
        raise EmvaError(str(p), f"unreadable or truncated image ({e})") from None
    if a.ndim != 2 or not np.issubdtype(a.dtype, np.integer):
        raise EmvaError(str(p), f"not a grayscale integer image (shape {a.shape}, {a.dtype})")
    if int(a.max()) >= 2 ** desc["bits"]:
        raise EmvaError(str(p), f"value {int(a.max())} does not fit the stated {desc['bits']} bits")
    desc["max_seen"] = max(desc.get("max_seen", 0), int(a.max()))   # check_data compares it with the bits
    return a.astype(np.int64)


def _pair(s_, desc):
    a, b = (load_image(p, desc) for p in s_["imgs"])
    mean = 0.5 * (a.mean() + b.mean())
    var = 0.5 * np.mean(np.square(a - b)) - 0.5 * (a.mean() - b.mean()) ** 2
    return mean, var


def temporal_data(desc: dict) -> dict:
    """Per exposure: dark mean/variance, and each bright step's (mu_p, mean, variance), as the reference."""
    by_t = {}
    for s_ in desc["steps"]:
        if len(s_["imgs"]) == 2:
            by_t.setdefault(s_["t"], []).append(s_)
    texp, u_p, u_y, s2_y, u_d, s2_d = [], [], [], [], [], []
    for t in sorted(by_t):
        darks = [s_ for s_ in by_t[t] if s_["kind"] == "d"]
        if not darks:
            raise EmvaError(desc["source"], f"exposure {t:g} s has bright steps but no dark step")
        md, vd = _pair(darks[0], desc)
        for s_ in sorted((s_ for s_ in by_t[t] if s_["kind"] == "b"), key=lambda x: x["mu_p"]):
            m, v = _pair(s_, desc)
            texp.append(t)
            u_p.append(s_["mu_p"])
            u_y.append(m)
            s2_y.append(v)
            u_d.append(md)
            s2_d.append(vd)
    if not u_y:
        raise EmvaError(desc["source"], "no bright step shares an exposure time with a dark step")
    return {k: np.array(v) for k, v in (("texp", texp), ("u_p", u_p), ("u_y", u_y), ("s2_y", s2_y),
                                          ("u_ydark", u_d), ("s2_ydark", s2_d))}


def _stack(s_, desc):
    imgs = np.array([load_image(p, desc) for p in s_["imgs"]], float)
    L = imgs.shape[0]
    avg = imgs.mean(axis=0)
    var_mean = imgs.var(axis=0, ddof=1).mean()
    return {"L": L, "avg_mean": avg.mean(), "avg_var": avg.var(ddof=1), "var_mean": var_mean}


def _slope0(x, y):
    return float(np.sum(x * y) / np.sum(x * x))


def _index_sat(s2_y):
    """The reference's scan for the variance maximum (from the top exposure down)."""
    max_, max_i = 0.0, 0
    for i in range(len(s2_y) - 1, -1, -1):
        if s2_y[i] >= max_ or s2_y[abs(i - 1)] >= max_:
            max_, max_i = s2_y[i], i
        elif s2_y[i] < max_ and s2_y[abs(i - 1)] < max_:
            break
    return max_i


def figures(desc: dict, tp: dict | None = None) -> dict:
    """The EMVA 1288 figures of a dataset, computed as the reference implementation does."""
    tp = temporal_data(desc) if tp is None else tp
    Y = tp["u_y"] - tp["u_ydark"]
    V = tp["s2_y"] - tp["s2_ydark"]
    i_sat = _index_sat(tp["s2_y"])
    i_max = int(np.max(np.nonzero(Y <= 0.7 * Y[i_sat])[0]))
    sl = slice(0, i_max + 1)
    K = _slope0(Y[sl], V[sl])
    R = _slope0(tp["u_p"][sl], Y[sl])
    qe = 100.0 * R / K
    texp = tp["texp"]
    multi = np.unique(texp).size > 2
    s2_dark = float(np.polyfit(texp, tp["s2_ydark"], 1)[1]) if multi else float(tp["s2_ydark"][0])
    s2_dark = max(s2_dark, 0.24)
    sigma_y_dark = np.sqrt(s2_dark)
    u_p_min = (100.0 / qe) * (sigma_y_dark / K + 0.5)
    u_p_sat = float(tp["u_p"][i_sat])
    u_e_sat = qe * u_p_sat / 100.0
    lo = int(np.min(np.nonzero(Y >= 0.05 * Y[i_sat])[0]))
    hi = int(np.max(np.nonzero(Y <= 0.95 * Y[i_sat])[0])) + 1
    X_, Y_ = tp["u_p"][lo:hi], Y[lo:hi]
    xy, xy2, x2y2 = np.sum(X_ / Y_), np.sum(X_ / Y_ ** 2), np.sum((X_ / Y_) ** 2)
    _y, _y2 = np.sum(1 / Y_), np.sum(1 / Y_ ** 2)
    b = (xy * xy2 - x2y2 * _y) / (xy2 ** 2 - x2y2 * _y2)
    a = (xy - b * xy2) / x2y2
    dev = 100.0 * (Y - (a * tp["u_p"] + b)) / (a * tp["u_p"] + b)
    per_s = 1.0  # texp is in seconds already
    if multi:
        m_slope = float(np.polyfit(texp, tp["u_ydark"], 1)[0]) * per_s
        v_slope = float(np.polyfit(texp, tp["s2_ydark"], 1)[0]) * per_s
    else:
        m_slope = v_slope = float("nan")
    dark_var_DN = v_slope / K if multi and v_slope >= 0 else float("nan")
    out = {"K_DN_per_e": K, "R_DN_per_photon": R, "QE_percent": qe, "sigma_y_dark_DN": float(sigma_y_dark),
           "sigma_d_e": float(np.sqrt(s2_dark - S2Q) / K), "u_p_min": float(u_p_min), "u_p_sat": u_p_sat,
           "u_e_sat": float(u_e_sat), "SNR_max": float(np.sqrt(u_e_sat)), "SNR_max_dB": float(20 * np.log10(np.sqrt(u_e_sat))),
           "DR": float(u_p_sat / u_p_min), "DR_dB": float(20 * np.log10(u_p_sat / u_p_min)),
           "LE_min_percent": float(np.min(dev[lo:hi])), "LE_max_percent": float(np.max(dev[lo:hi])),
           "dark_current_mean_DN_per_s": m_slope, "dark_current_mean_e_per_s": m_slope / K,
           "dark_current_var_DN_per_s": dark_var_DN, "dark_current_var_e_per_s": dark_var_DN / K,
           "index_saturation": int(i_sat), "bits": desc["bits"], "exposure_unit": desc["exposure_unit"]}
    spatial = [s_ for s_ in desc["steps"] if len(s_["imgs"]) > 2]
    dark_st = [s_ for s_ in spatial if s_["kind"] == "d"]
    bright_st = [s_ for s_ in spatial if s_["kind"] == "b"]
    if dark_st and bright_st:
        d, br = _stack(dark_st[0], desc), _stack(bright_st[0], desc)
        s2y_d = d["avg_var"] - d["var_mean"] / d["L"]
        s2y = br["avg_var"] - br["var_mean"] / br["L"]
        out["DSNU_e"] = float(np.sqrt(s2y_d) / K) if s2y_d >= 0 else float("nan")
        out["PRNU_percent"] = float(np.sqrt(s2y - s2y_d) * 100 / (br["avg_mean"] - d["avg_mean"])) \
            if s2y >= s2y_d else float("nan")
    return out


def _dark_noise_verdict(fig) -> dict | None:
    m, v = fig["dark_current_mean_e_per_s"], fig["dark_current_var_e_per_s"]
    if m is None or v is None or v <= 0:
        return None
    if m <= 0:   # the dark variance grows while the dark mean does not
        return {"effect": "non_poisson_dark_noise", "ratio_var_to_mean": None,
                "text": "the dark variance grows with exposure while the dark mean does not: the dark signal is "
                        "not shot-noise limited (RTS / hot pixels, or a drifting dark offset)"}
    ratio = v / m
    if 1 / 1.5 <= ratio <= 1.5:
        return None
    return {"effect": "non_poisson_dark_noise", "ratio_var_to_mean": float(ratio),
            "text": f"dark current from the variance is {ratio:.2g} x that from the mean: the dark signal is not "
                    f"shot-noise limited (RTS / hot pixels, or a drifting dark offset)"}


def measure_steps(desc: dict, tp: dict) -> dict:
    """Bright (t, mu_p, mean, var) and dark (t, 0, mean, var) arrays for the gap analysis."""
    b = np.column_stack([tp["texp"], tp["u_p"], tp["u_y"], tp["s2_y"]])
    _, first = np.unique(tp["texp"], return_index=True)
    d = np.column_stack([tp["texp"][first], np.zeros(first.size), tp["u_ydark"][first], tp["s2_ydark"][first]])
    return {"b": b, "d": d}


def nominal_fit(m: dict, full_scale: float, fig: dict) -> dict:
    """The linear camera model with the figures' K and R (the reference's fits).

    ``sigma_d_measured_e`` is the dark temporal noise the dark steps show (less the quantisation
    noise), the noise model of the gap analysis; the figures' ``sigma_d_e`` is the standard's,
    computed as the reference implementation does from at least 0.24 DN^2, so on a camera whose
    dark noise is below that floor the two differ (docs/howto-emva1288.md)."""
    t, mu_p, mu, var = m["b"].T
    td, _, mud, vard = m["d"].T
    mu_sat = mu[fig["index_saturation"]]
    K, R = fig["K_DN_per_e"], fig["R_DN_per_photon"]
    D = np.polyfit(td, mud, 1)[0] if td.size > 1 else 0.0
    return {"K_DN_per_e": float(K), "R_DN_per_photon": float(R), "eta": float(R / K),
            "dark_DN": float(mud.mean()), "dark_current_DN_per_s": float(D), "dark_t_mean": float(td.mean()),
            "sigma_dark_DN": float(np.sqrt(vard.mean())),
            "sigma_d_measured_e": float(np.sqrt(max(vard.mean() - 1 / 12, 0)) / K),
            "mu_sat_DN": float(mu_sat), "full_scale_DN": full_scale,
            "mu_e_sat": float((mu_sat - mud.mean()) / K), "snr_max_dB": float(20 * np.log10(np.sqrt((mu_sat - mud.mean()) / K)))}


def _mean_model(mu_p, t, nom, effect=None, p=()):
    # the dark level at the step's exposure (the dark frames' line: mu_y = mu_y.dark(t) + R mu_p, as the standard
    # subtracts the dark of the same exposure), not their mean
    mu_d = nom["dark_DN"] + nom["dark_current_DN_per_s"] * (t - nom["dark_t_mean"])
    R, fs = nom["R_DN_per_photon"], nom["full_scale_DN"]
    sig = R * mu_p
    if effect == "nonlinearity":
        sig = sig * (1 - p[0] * sig)
    if effect == "dark_current":
        mu_d = mu_d + p[0] * t
    x = mu_d + sig
    # a step's mean is E[min(X, fs)] over its pixels' values, X ~ N(x, s^2): a linear camera's own temporal noise
    # (shot K sig and dark) already loses the tail beyond the full-scale code as a step nears it (the nominal model;
    # a hard min(x, fs) read that as a gap); soft saturation spreads the pixels further (p[0]: a per-pixel
    # saturation / gain spread relative to the signal)
    spread = p[0] if effect == "soft_saturation" else 0.0
    s = np.sqrt((spread * sig) ** 2 + nom["K_DN_per_e"] * np.maximum(sig, 0.0) + nom["sigma_dark_DN"] ** 2)
    z = (fs - x) / s
    return x - s * (norm.pdf(z) - z * norm.sf(z))


CANDIDATES = {"nonlinearity": ([1e-4], [0.0], [1e-2]), "soft_saturation": ([0.02], [0.0], [0.5]),
              "dark_current": ([0.0], [-1e3], [1e3])}


#: Figures a dataset may not determine (one or two exposures; a negative variance slope; no
#: spatial stacks): None in the answer, "n/a" in the text, never NaN.
OPTIONAL = ("dark_current_mean_DN_per_s", "dark_current_mean_e_per_s", "dark_current_var_DN_per_s",
            "dark_current_var_e_per_s", "DSNU_e", "PRNU_percent")


def check_data(desc: dict, tp: dict) -> None:
    """Refuse, naming what is missing, data from which the figures cannot be computed: no exposure,
    photon counts that do not grow with exposure, a bit depth the data do not use, every bright
    step saturated, no signal above the dark level, no photon-transfer range below saturation."""
    src = desc["source"]
    bright = [s_ for s_ in desc["steps"] if s_["kind"] == "b" and len(s_["imgs"]) == 2]
    if all(s_["t"] == 0 for s_ in desc["steps"]):
        raise EmvaError(src, "every exposure is 0: no photons can be collected (check the 'b' and 'd' lines)")
    by_t = {}
    for s_ in bright:
        by_t.setdefault(s_["t"], []).append(s_)
    if len(by_t) > 1 and all(len(v) == 1 for v in by_t.values()):   # the exposure-variation method
        steps = [v[0] for _, v in sorted(by_t.items())]
        for a, b in zip(steps, steps[1:]):
            if b["mu_p"] <= a["mu_p"]:
                raise EmvaError(f"{src}:{b['line']}", f"photons {b['mu_p']:g} at exposure {b['t_raw']:g} do not exceed "
                                f"{a['mu_p']:g} at the shorter exposure {a['t_raw']:g} (line {a['line']}): photon "
                                "counts must grow with exposure")
    fs = 2 ** desc["bits"] - 1
    if np.all(tp["u_y"] >= fs - 0.5):
        raise EmvaError(src, f"every bright step is saturated (mean at the full scale {fs} DN): no signal range")
    Y = tp["u_y"] - tp["u_ydark"]
    floor = max(1.0, 3.0 * float(np.sqrt(max(np.mean(tp["s2_ydark"]), 0.0))))
    if Y.max() <= floor:
        raise EmvaError(src, f"no signal range: the bright means exceed the dark means by at most {Y.max():.3g} DN "
                             f"(noise floor {floor:.3g} DN)")
    if np.all(tp["s2_y"] - tp["s2_ydark"] <= 0):
        raise EmvaError(src, "no photon noise: the two images of every bright step vary no more than the dark "
                             "ones (identical or synthetic images?)")
    bits, top = desc["bits"], desc.get("max_seen", 0)
    if bits >= 5 and top < 2 ** (bits - 4):
        used = max(int(top).bit_length(), 1)
        raise EmvaError(src, f"the descriptor states {bits} bits, but the largest value in the images is {top} "
                             f"({used} bits): state the camera's bit depth")


def analyse(folder) -> dict:
    """EMVA 1288 figures plus the camera-level gap: where the data leave the linear model, and why."""
    import warnings
    desc = read_descriptor(folder)
    tp = temporal_data(desc)
    check_data(desc, tp)
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore")   # degenerate fits are refused below, by name, not as warnings
        return _analyse(desc, tp)


def _analyse(desc: dict, tp: dict) -> dict:
    fig = figures(desc, tp)
    for k in OPTIONAL:
        if k in fig and not np.isfinite(fig[k]):
            fig[k] = None
    bad = [k for k, v in fig.items() if isinstance(v, float) and not np.isfinite(v)]
    if bad or not fig["K_DN_per_e"] > 0 or not fig["R_DN_per_photon"] > 0:
        raise EmvaError(desc["source"], f"the photon transfer cannot be computed from these data "
                                        f"(K = {fig['K_DN_per_e']:.3g} DN/e-, R = {fig['R_DN_per_photon']:.3g}"
                                        f"{'; not finite: ' + ', '.join(bad) if bad else ''}): fewer than two "
                                        "bright steps with signal below 70 % of saturation?")
    m = measure_steps(desc, tp)
    fs = 2 ** desc["bits"] - 1
    nom = nominal_fit(m, float(fs), fig)
    t, mu_p, mu, var = m["b"].T
    train = np.arange(mu.size) % 2 == 0
    test = ~train
    keep = mu < fs - 0.5     # fully clipped steps carry no information on the response
    pred0 = _mean_model(mu_p, t, nom)
    resid = mu - pred0
    frac = (mu - nom["dark_DN"]) / (nom["mu_sat_DN"] - nom["dark_DN"])
    where = []
    for lo, hi in ((0, 0.1), (0.1, 0.7), (0.7, 0.9), (0.9, 1.0), (1.0, 2.0)):
        sel = (frac >= lo) & (frac < hi)
        if sel.any():
            k_pred = nom["sigma_dark_DN"] ** 2 + nom["K_DN_per_e"] * np.maximum(mu[sel] - nom["dark_DN"], 0)
            where.append({"region": f"{lo * 100:.0f}-{hi * 100:.0f} % of saturation", "n": int(sel.sum()),
                          "mean_resid_DN": float(resid[sel].mean()),
                          "rms_resid_DN": float(np.sqrt(np.mean(resid[sel] ** 2))),
                          "var_resid_rel": float(np.mean(var[sel] / k_pred - 1))})
    n_pix = 2.0 * desc["width"] * desc["height"]
    sigma = np.sqrt((np.maximum(var, 0.0) + S2Q) / n_pix)
    fits = {"none": ((), pred0)}
    for name, (x0, lo, hi) in CANDIDATES.items():
        f = (lambda p, name=name: (_mean_model(mu_p[train & keep], t[train & keep], nom, name, p)
                                   - mu[train & keep]) / sigma[train & keep])
        r = least_squares(f, x0, bounds=(lo, hi))
        fits[name] = (tuple(r.x), _mean_model(mu_p, t, nom, name, r.x))
    verdict = camera_verdict(fits, mu, sigma, train & keep, test & keep)
    ranking = [{"effect": name, "params": dict(zip(["value"], [float(x) for x in p])),
                "heldout_rms_DN": float(np.sqrt(np.mean((pred - mu)[test & keep] ** 2))),
                "heldout_max_DN": float(np.max(np.abs(pred - mu)[test & keep])),
                **verdict["per_model"][name]} for name, (p, pred) in fits.items()]
    ranking.sort(key=lambda x: x["heldout_chi2"])
    rms = {x["effect"]: x["heldout_rms_DN"] for x in ranking}
    shown = verdict["best"] if verdict["best"] != "none" else (verdict["best_partial"] or "none")
    dark_noise = _dark_noise_verdict(fig)
    text = verdict["verdict"] + (f"; in the dark frames: {dark_noise['effect']}" if dark_noise else "")
    return {"figures": fig, "dark_noise": dark_noise, "dataset": desc["source"], "n_bright_steps": int(mu.size),
            "n_dark_steps": int(m["d"].shape[0]), "nominal": nom, "where": where, "ranking": ranking,
            "best": verdict["best"], "explained": verdict["explained"], "best_partial": verdict["best_partial"],
            "indistinguishable": verdict["indistinguishable"], "verdict": text,
            "fit_p_value": verdict["per_model"][shown]["heldout_p"],
            "noise_rms_DN": float(np.sqrt(np.mean(sigma[test & keep] ** 2))),
            "noise_source": "each step's mean: its pair's temporal variance and the quantisation over its pixels",
            "gap_before_rms_DN": rms["none"], "gap_after_rms_DN": rms[shown],
            "shrink_frac": 1 - rms[shown] / rms["none"] if rms["none"] > 0 else 0.0,
            "dark_level_spread_DN": float(np.ptp(m["d"][:, 2]))}


def camera_verdict(fits: dict, mu, sigma, train, test) -> dict:
    """The camera-level answer in the statistics and words of ``gap diagnose`` (``diagnose``): a candidate beats
    the linear model when its held-out chi-square is lower by more than the (1 - P_BEAT) point of chi-square(k)
    and its training chi-square + k ln n (BIC) by ``BIC_MARGIN``; the lowest held-out chi-square of those is
    named, those within ``AMBIGUOUS_DCHI2`` of it are listed as indistinguishable; explained when the named
    model's held-out chi-square is consistent with the steps' noise (p >= P_EXPLAINED)."""
    from .diagnose import AMBIGUOUS_DCHI2, BIC_MARGIN, P_BEAT, P_EXPLAINED, verdict_text
    from .pvalue import chi2_isf, chi2_sf
    n_tr, n_te = int(train.sum()), int(test.sum())
    per = {}
    for name, (p, pred) in fits.items():
        r = (pred - mu) / sigma
        c_te, c_tr = float(np.sum(r[test] ** 2)), float(np.sum(r[train] ** 2))
        per[name] = {"heldout_chi2": c_te, "heldout_chi2_per_row": c_te / max(n_te, 1), "n_params": len(p),
                     "bic": c_tr + len(p) * float(np.log(max(n_tr, 1))), "heldout_p": float(chi2_sf(c_te, n_te))}
    none = per["none"]
    for name, x in per.items():
        x["beats_none"] = bool(name != "none"
                               and none["heldout_chi2"] - x["heldout_chi2"] > chi2_isf(P_BEAT, max(x["n_params"], 1))
                               and none["bic"] - x["bic"] > BIC_MARGIN)
    winners = sorted((n for n, x in per.items() if x["beats_none"]), key=lambda n: per[n]["heldout_chi2"])
    best = winners[0] if winners else "none"
    ambiguous = [n for n in winners[1:] if per[n]["heldout_chi2"] - per[best]["heldout_chi2"] < AMBIGUOUS_DCHI2]
    explained = bool(per[best]["heldout_p"] >= P_EXPLAINED)
    top = min((n for n in per if n != "none"), key=lambda n: per[n]["heldout_chi2"])
    return {"best": best, "explained": explained, "indistinguishable": ambiguous,
            "best_partial": (best if best != "none" else top) if not explained else None,
            "verdict": verdict_text(best, explained, ambiguous, top=top), "per_model": per}


