"""The harness's figures (matplotlib, Agg): scatter d_a vs d_b, |Δd| histogram, timing bars; for a pair with a
verdicts-only backend (no distances to scatter) a verdict bar chart per category instead."""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["write_plots"]

_MAX_POINTS = 60_000  # scatter points drawn per backend pair (a seeded subsample, disagreements always kept)


def _subplots(nrows: int = 1, ncols: int = 1, **fig_kw):
    """``(figure, axes)`` as ``pyplot.subplots`` gives them, from ``matplotlib.figure.Figure`` itself:
    no pyplot, so the caller's backend and open figures are left as they were (``matplotlib.use``
    here switched a user's backend to Agg) and threads share no pyplot state."""
    from matplotlib.figure import Figure

    fig = Figure(**fig_kw)
    return fig, fig.subplots(nrows, ncols)


def _save(fig, p: Path) -> None:
    """The figure at ``p`` (a PNG, or the format its suffix names), all or nothing (``armguard._io.save_figure``)."""
    from .._io import save_figure

    save_figure(fig, p, dpi=110, bbox_inches="tight")


def write_plots(comparison, out_dir) -> list:
    """Write ``scatter_<a>_<b>.png``, ``hist_<a>_<b>.png`` per backend pair (``verdicts_<a>_<b>.png`` where a side
    answers verdicts only) and ``timing.png``; returns the paths."""
    from .._io import make_folder

    out = make_folder(out_dir)
    written = []
    band = comparison.summary["tolerances"]["contact_band"]
    cats = np.asarray(comparison.model.pairs.category, dtype=object)
    rng = np.random.default_rng(0)
    for key, s in comparison.summary["pairs"].items():
        a, b = s["a"], s["b"]
        if s.get("answers") == "verdicts":
            written.append(_verdict_bars(comparison, s, out))
            continue
        A, B = comparison.answers[a].distance, comparison.answers[b].distance
        R = comparison.answers[s["reference"]].distance
        fig, ax = _subplots(figsize=(6, 6))
        flat_a, flat_b, flat_r = A.ravel(), B.ravel(), R.ravel()
        flat_c = np.broadcast_to(cats, A.shape).ravel()
        sign_bad = ((flat_a <= 0) != (flat_b <= 0)) & (np.abs(flat_r) > band)
        keep = np.arange(flat_a.size)
        if keep.size > _MAX_POINTS:
            keep = np.union1d(rng.choice(keep, _MAX_POINTS, replace=False), np.flatnonzero(sign_bad))
        for c in dict.fromkeys(cats):
            sel = keep[flat_c[keep] == c]
            ax.scatter(flat_b[sel], flat_a[sel], s=2, alpha=0.5, label=c, rasterized=True)
        bad = np.flatnonzero(sign_bad)
        if bad.size:
            ax.scatter(flat_b[bad], flat_a[bad], s=14, facecolors="none", edgecolors="red",
                       label=f"opposite verdicts outside band ({bad.size})")
        lo = float(min(flat_a.min(initial=0), flat_b.min(initial=0)))
        hi = float(max(flat_a.max(initial=1), flat_b.max(initial=1)))
        ax.plot([lo, hi], [lo, hi], "k-", lw=0.5)
        ax.axvspan(-band, band, color="orange", alpha=0.3, label=f"contact band |d| <= {band:g} m")
        ax.axhspan(-band, band, color="orange", alpha=0.3)
        ax.axhline(0, color="k", lw=0.3), ax.axvline(0, color="k", lw=0.3)
        ax.set_xlabel(f"{b} distance (m)"), ax.set_ylabel(f"{a} distance (m)")
        ax.set_title(f"{comparison.model.name}: {a} vs {b}, {A.shape[0]} configurations x {A.shape[1]} pairs")
        ax.legend(fontsize=7, markerscale=3, loc="upper left")
        p = out / f"scatter_{a}_{b}.png"
        _save(fig, p)
        written.append(p)

        fig, ax = _subplots(figsize=(7, 4))
        err = np.abs(A - B)
        floor = 1e-17
        bins = np.linspace(-17, 1, 73)
        for c in dict.fromkeys(cats):
            e = err[:, cats == c].ravel()
            ax.hist(np.log10(np.maximum(e, floor)), bins=bins, histtype="step", label=c)
        ax.set_yscale("log")
        ax.set_xlabel("log10 |d_a - d_b| (m)  (0 plotted at -17)")
        ax.set_ylabel("(configuration, pair) entries")
        ax.set_title(f"{comparison.model.name}: |Δd| {a} vs {b}")
        ax.legend(fontsize=7)
        p = out / f"hist_{a}_{b}.png"
        _save(fig, p)
        written.append(p)

    fig, (ax1, ax2) = _subplots(1, 2, figsize=(9, 3.5))
    per = comparison.summary["backends"]
    names = list(per)
    dist = [n for n in names if per[n].get("answers") != "verdicts"]
    us = [per[n]["us_per_config"] for n in dist]
    yn = [per[n]["yes_no_configs_per_s"] for n in names]
    ax1.bar(dist, us, color="tab:blue")
    skipped = [n for n in names if n not in dist]
    ax1.set_ylabel("µs per configuration")
    ax1.set_title("distances + witness points" + (f"\n({', '.join(skipped)}: n/a, verdicts only)" if skipped else ""))
    ax1.set_yscale("log")
    ax2.bar(names, yn, color="tab:green")
    ax2.set_ylabel("configurations / s"), ax2.set_title("yes/no (collides batch)")
    ax2.set_yscale("log")
    for ax, vals in ((ax1, us), (ax2, yn)):
        for i, v in enumerate(vals):
            ax.annotate(f"{v:.3g}", (i, v), ha="center", va="bottom", fontsize=8)
    fig.suptitle(f"{comparison.model.name}: {len(comparison.configs)} configurations")
    p = out / "timing.png"
    _save(fig, p)
    written.append(p)
    return written


def _verdict_bars(comparison, s, out: Path) -> Path:
    """``verdicts_<a>_<b>.png``: per category, the shares of configurations the verdicts-only side answers
    wrongly clear (unsafe), wrongly as a definite collision, undecided (first level and final), and
    conservatively (said collision, clear), with the counts annotated."""
    a, b = s["a"], s["b"]
    if "sides" in s:  # two verdicts-only backends: each against the reference
        cats = {f"{side}: {c}": r for side, d in s["sides"].items() for c, r in d["categories"].items()}
    else:
        cats = {c: r for c, r in s["categories"].items() if "reference_collisions" in r}
    M = max(1, len(comparison.configs))
    und = "map-forbidden" if s.get("false_forbidden") else "MAYBE"
    bars = [("said clear, collides (unsafe)", lambda r: r["clear_but_collides"] / M if r["clear_but_collides"] is not None else None, "tab:red"),
            ("definite collision, clear", lambda r: r["collision_but_clear"] / M if r["collision_but_clear"] is not None else None, "tab:purple"),
            (f"{und}, first level", lambda r: r["undecided_share_first_level"], "tab:orange"),
            (und, lambda r: r["undecided_share"], "gold"),
            ("said collision, clear (conservative)", lambda r: r["conservative_share"], "tab:blue")]
    ff = s.get("false_forbidden")
    fig, ax = _subplots(figsize=(max(6, 1.8 * len(cats) + 3), 4))
    width = 0.8 / len(bars)
    for j, (label, get, colour) in enumerate(bars):
        xs, ys = [], []
        for i, r in enumerate(cats.values()):
            y = get(r)
            if y is not None:
                xs.append(i + (j - (len(bars) - 1) / 2) * width)
                ys.append(100 * y)
        if xs:
            ax.bar(xs, ys, width=width, color=colour, label=label)
            for x, y in zip(xs, ys):
                ax.annotate(f"{y:.2f}", (x, y), ha="center", va="bottom", fontsize=6)
    ax.set_xticks(range(len(cats)), list(cats))
    ax.set_ylabel("% of configurations")
    title = (f"{comparison.model.name}: {', '.join(s['verdicts_only'])} (verdicts only) vs {s['reference']}, "
             f"{len(comparison.configs)} configurations; unsafe {s.get('unsafe_disagreements')}")
    if ff:
        title += f"; false-forbidden {100 * ff['share']:.2f} %"
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7)
    p = out / f"verdicts_{a}_{b}.png"
    _save(fig, p)
    return p
