"""``fibersweep explore``: one self-contained HTML page to browse a sweep.

The page holds the runs table, each run's trajectory (thinned) and the pillar
outlines as JSON, the plotly.js library inlined (from the ``plotly`` Python
package, no network), and a little script of its own:

* a phase diagram (θ0, y0/h_obs), one trace per class; hovering a run shows
  every column of its row (settings and outcome);
* one filter per column (a range for numbers, tick boxes for a few values);
  the diagram and the count follow at once;
* clicking a run draws its trajectory over its pillar (centre-of-mass path,
  the fiber at regular times coloured by time) and lists its row.

A pillar array's runs (``mode`` set) are shown in the array's terms: the
displacement fraction f against the fiber length, one trace per mode (runs of
different settings side by side), and a clicked run's path through the rows,
in µm, over the pillars it passed. A fiber is drawn through every bead when its
bead positions were stored; a bead-spring fiber without them is not drawn (its
straight chord would cut through the pillar it bends around) and the page says
how to keep them (:mod:`fibersweep.plots.shapes`).

Plotly was chosen because its JavaScript library ships inside the Python
wheel, so one ``pip install`` gives an offline page with hover, zoom and
click events, and it is maintained by a company and a large community.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from html import escape

import numpy as np
import pandas as pd
from matplotlib.colors import to_hex

from fibersweep.analysis.modes import MODES
from fibersweep.analysis.trajectory import CLASSES
from fibersweep.plots.shapes import ShapeNotStored, fiber_points
from fibersweep.plots.style import CLASS_STYLE, FAILED_STYLE, MODE_STYLE, UNCLASSIFIED_STYLE
from fibersweep.plots.tracks import _outline, normalised
from fibersweep.units import Geometry

#: Fiber positions drawn for a clicked run.
FIBER_FRAMES = 16

__all__ = ["explorer_data", "explorer_html"]

#: Plotly marker symbols of the class markers (same shapes as the matplotlib figures).
_SYMBOLS = {"o": "circle", "s": "square", "^": "triangle-up", "v": "triangle-down",
            "D": "diamond", "P": "cross", "x": "x"}  # fmt: skip

#: Columns left out of the page (bookkeeping nobody filters by).
_HIDDEN = ("worker", "finished_at", "attempts", "cpu_time")
#: The channel's outcome columns, empty in a pillar array's runs: left out of its page.
_CHANNEL_ONLY = ("class", "delta", "theta_c", "y_c", "t_contact", "t_pass")


def _jsonable(v: object) -> object:
    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, float) and not math.isfinite(v):
        return None
    if v is None or isinstance(v, bool | int | float | str):
        return v
    if pd.isna(v):  # type: ignore[arg-type]
        return None
    return str(v)


def _fibers(s: pd.DataFrame, run: pd.Series, to_page, near) -> dict:
    """The fiber at up to FIBER_FRAMES samples of ``near`` (indices into ``s``), in page
    units: ``fibers`` (list of [xs, ys]) and ``fiber_t``, or ``fibers`` None and ``note``."""
    if len(near) < 2:
        near = np.arange(len(s))
    m = min(FIBER_FRAMES, len(near))
    picks = near[np.round(np.linspace(0, len(near) - 1, m)).astype(int)]
    has_beads = "beads" in s.columns
    out = []
    try:
        for i in picks:
            beads = s["beads"].iloc[i] if has_beads else None
            beads = None if beads is None or (np.size(beads) == 0) else np.asarray(beads)
            ends = (s[["tail_x", "tail_y"]].iloc[i].to_numpy(float),
                    s[["head_x", "head_y"]].iloc[i].to_numpy(float))  # fmt: skip
            pts = to_page(fiber_points(run.get("model"), int(run.get("n_beads") or 0), beads,
                                       ends=ends))  # fmt: skip
            out.append([np.round(pts[:, 0], 4).tolist(), np.round(pts[:, 1], 4).tolist()])
    except ShapeNotStored:
        return {"fibers": None, "note": "bead-spring fiber stored without its bead positions "
                "(set fiber.record.all_beads: true to draw its shape)"}  # fmt: skip
    t = s["t"].to_numpy(dtype=float)[picks]
    return {"fibers": out, "fiber_t": np.round(t, 4).tolist()}


def explorer_data(
    runs: pd.DataFrame,
    samples: pd.DataFrame,
    geometries: Mapping[str, Geometry],
    *,
    separatrix: float | None = None,
    n_samples: int = 150,
    arrays: Mapping[str, object] | None = None,
) -> dict:
    """What the page needs, as plain JSON-able data.

    Parameters
    ----------
    runs : DataFrame
        The runs table.
    samples : DataFrame
        Trajectory rows of (some of) the runs.
    geometries : mapping of settings id -> Geometry
        The channel of each setting (unused for array runs).
    separatrix : float, optional
        Far-upstream y/h_obs of the separatrix.
    n_samples : int
        Most points kept per trajectory (evenly spaced samples, the last kept).
    arrays : mapping of settings id -> PillarArray, optional
        For pillar-array runs: the array of each setting (the page then shows f
        against length, and paths in µm over the pillars).

    Returns
    -------
    dict
        ``columns``, ``rows`` (lists in column order), ``tracks`` (id -> t, x, y,
        ``fibers`` (the fiber at regular times, each [xs, ys]) and ``fiber_t``;
        channel: in h_obs from the pillar's base centre; array: in µm),
        ``outlines`` (settings id -> polygon), ``lattices`` (array: settings id ->
        pillar outline [µm] and the lattice periods), ``styles`` (class or mode ->
        colour, symbol), ``frame`` ('channel' or 'array'), ``separatrix``.
    """
    array = arrays is not None
    hidden = (*_HIDDEN, *_CHANNEL_ONLY) if array else _HIDDEN
    cols = [c for c in runs.columns if c not in hidden and not (array and c.startswith("class_"))]
    rows = [[_jsonable(v) for v in r] for r in runs[cols].itertuples(index=False, name=None)]
    tracks = {}
    by_id = runs.set_index("id")
    settings = by_id["settings"].astype(str).to_dict()
    for rid, s in samples.groupby("id", sort=False) if len(samples) else ():
        if rid not in settings or len(s) < 2:
            continue
        s = s.sort_values("sample").reset_index(drop=True)
        keep = np.unique(np.linspace(0, len(s) - 1, min(n_samples, len(s))).round().astype(int))
        run = by_id.loc[rid]
        if array:
            x = s["x"].to_numpy(dtype=float)
            tr = {"x": np.round(x[keep], 3).tolist(),
                  "y": np.round(s["y"].to_numpy(dtype=float)[keep], 3).tolist()}  # fmt: skip
            near = np.arange(len(s))
            tr.update(_fibers(s, run, lambda p: p, near))
        else:
            g = geometries[settings[rid]]
            p = normalised(s.iloc[keep], g)
            tr = {k: np.round(v, 4).tolist() for k, v in p.items()}
            xb, yb = g.base_center
            h = g.pillar_height
            px = _outline(g)[:, 0]
            xn = (s["x"].to_numpy(dtype=float) - xb) / h
            near = np.flatnonzero((xn > px.min() - 2) & (xn < px.max() + 2))
            tr.update(_fibers(s, run, lambda q, xb=xb, yb=yb, h=h: (q - [xb, yb]) / h, near))
        tr["t"] = np.round(s["t"].to_numpy(dtype=float)[keep], 4).tolist()
        tracks[str(rid)] = tr
    base = MODE_STYLE if array else CLASS_STYLE
    styles = {
        c: {"color": to_hex(st["color"]), "symbol": _SYMBOLS[str(st["marker"])]}
        for c, st in base.items()
    }
    styles["unclassified"] = {"color": to_hex(UNCLASSIFIED_STYLE["color"]), "symbol": "cross"}
    styles["failed"] = {"color": to_hex(FAILED_STYLE["color"]), "symbol": "x"}
    sep = float(separatrix) if separatrix is not None and math.isfinite(separatrix) else None
    lattices = {}
    if array:
        for sid, arr in arrays.items():
            outline = np.round(arr.shape.outline(48), 3).tolist()
            lattices[sid] = {
                "outline": outline, "px": arr.period_x, "py": arr.period_y,
                "ls": arr.lateral_shift,
            }  # fmt: skip
    return {
        "columns": cols,
        "rows": rows,
        "tracks": tracks,
        "outlines": {}
        if array
        else {sid: np.round(_outline(g), 4).tolist() for sid, g in geometries.items()},
        "lattices": lattices,
        "styles": styles,
        "classes": list(MODES if array else CLASSES),
        "frame": "array" if array else "channel",
        "separatrix": sep,
    }


def explorer_html(
    runs: pd.DataFrame,
    samples: pd.DataFrame,
    geometries: Mapping[str, Geometry],
    *,
    title: str = "sweep",
    separatrix: float | None = None,
    samples_per_run: int = 150,
    arrays: Mapping[str, object] | None = None,
) -> str:
    """The whole page as one string (plotly.js and the data inlined; no network access).

    Parameters as :func:`explorer_data` (``samples_per_run`` is its ``n_samples``);
    ``title`` names the folder on the page.
    """
    from plotly.offline import get_plotlyjs

    data = explorer_data(runs, samples, geometries, separatrix=separatrix,
                         n_samples=samples_per_run, arrays=arrays)  # fmt: skip
    payload = json.dumps(data, allow_nan=False, separators=(",", ":")).replace("</", "<\\/")
    return _PAGE.format(
        title=escape(title), plotly=get_plotlyjs(), data=payload, script=_SCRIPT, css=_CSS
    )


_CSS = """
body { font-family: sans-serif; font-size: 13px; margin: 0; display: flex; height: 100vh; }
#side { width: 280px; overflow-y: auto; padding: 8px; border-right: 1px solid #ccc; }
#main { flex: 1; display: flex; flex-direction: column; min-width: 0; }
#phase { height: 55%; } #traj { height: 45%; }
.filter { margin-bottom: 6px; } .filter b { display: block; }
.filter input[type=number] { width: 90px; }
#details { font-size: 12px; } #details td { padding: 0 6px 0 0; }
h1 { font-size: 15px; margin: 4px 0; } #count { font-weight: bold; margin: 4px 0; }
"""

_PAGE = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>fibersweep explore: {title}</title>
<style>{css}</style>
<script>{plotly}</script>
</head><body>
<div id="side"><h1>fibersweep explore</h1><div>{title}</div>
<div id="count"></div>
<button id="reset">clear filters</button>
<div id="filters"></div>
<h1>selected run</h1><table id="details"><tr><td>click a run in the diagram</td></tr></table>
</div>
<div id="main"><div id="phase"></div><div id="traj"></div></div>
<script id="data" type="application/json">{data}</script>
<script>{script}</script>
</body></html>
"""

_SCRIPT = r"""
const D = JSON.parse(document.getElementById('data').textContent);
const C = D.columns, R = D.rows, col = name => C.indexOf(name);
const ARRAY = D.frame === 'array';
const iClass = col(ARRAY ? 'mode' : 'class'), iStatus = col('status'), iId = col('id');
const iSet = col('settings');
// the diagram: channel (theta0, y0/h_obs); pillar array (L [µm], f)
const xCol = ARRAY ? 'length' : 'theta0', yCol = ARRAY ? 'fraction' : 'y0';
const filters = {};   // column -> function(value) -> bool
// runs that differ only in a setting (length, a swept key) would sit on one point:
// set them side by side along x by the first such setting that varies
const dodgeKey = C.filter(c => c.includes('.')).concat(ARRAY ? [] : ['length']).find(c =>
  col(c) >= 0 && new Set(R.map(r => r[col(c)])).size > 1);
const dodgeVals = dodgeKey ? [...new Set(R.map(r => r[col(dodgeKey)]))].sort(
  (a, b) => (a < b ? -1 : a > b ? 1 : 0)) : [null];
const thetas = [...new Set(R.map(r => r[col(xCol)]))].sort((a, b) => a - b);
const dTheta = thetas.length > 1 ? Math.min(...thetas.slice(1).map((v, j) => v - thetas[j])) : 1;
function xOf(r) {
  if (!dodgeKey) return r[col(xCol)];
  const j = dodgeVals.indexOf(r[col(dodgeKey)]), n = dodgeVals.length;
  return r[col(xCol)] + (j - (n - 1) / 2) * 0.6 * dTheta / n;
}

function category(r) {
  if (r[iStatus] !== 'ok') return 'failed';
  return D.classes.includes(r[iClass]) ? r[iClass] : 'unclassified';
}

function buildFilters() {
  const box = document.getElementById('filters');
  C.forEach((name, j) => {
    const vals = R.map(r => r[j]).filter(v => v !== null);
    const uniq = [...new Set(vals)];
    const div = document.createElement('div');
    div.className = 'filter'; div.dataset.col = name;
    div.innerHTML = '<b>' + name + '</b>';
    if (vals.length && vals.every(v => typeof v === 'number') && uniq.length > 1) {
      const lo = Math.min(...vals), hi = Math.max(...vals);
      div.innerHTML += '<input type="number" step="any" class="lo" placeholder="' + fmt(lo) +
        '"> to <input type="number" step="any" class="hi" placeholder="' + fmt(hi) + '">';
      div.querySelectorAll('input').forEach(inp => inp.addEventListener('input', () => {
        const a = parseFloat(div.querySelector('.lo').value);
        const b = parseFloat(div.querySelector('.hi').value);
        filters[name] = v => v !== null && (isNaN(a) || v >= a) && (isNaN(b) || v <= b);
        draw();
      }));
    } else if (uniq.length > 1 && uniq.length <= 30) {
      uniq.sort();
      uniq.forEach(u => {
        const lab = document.createElement('label');
        lab.innerHTML = '<input type="checkbox" checked value="' + String(u) + '"> ' + String(u) +
          ' ';
        div.appendChild(lab);
      });
      div.querySelectorAll('input').forEach(inp => inp.addEventListener('change', () => {
        const on = [...div.querySelectorAll('input:checked')].map(x => x.value);
        filters[name] = v => on.includes(String(v));
        draw();
      }));
    } else if (uniq.length > 30) {
      div.innerHTML += '<input type="text" class="txt" placeholder="contains">';
      div.querySelector('input').addEventListener('input', e => {
        const s = e.target.value;
        filters[name] = v => String(v).includes(s);
        draw();
      });
    } else {
      div.innerHTML += ' <span>' + String(uniq[0]) + ' (all runs)</span>';
    }
    box.appendChild(div);
  });
  document.getElementById('reset').addEventListener('click', () => {
    for (const k in filters) delete filters[k];
    box.querySelectorAll('input[type=number], input[type=text]').forEach(x => x.value = '');
    box.querySelectorAll('input[type=checkbox]').forEach(x => x.checked = true);
    draw();
  });
}

function fmt(v) {
  if (v === null) return '-';
  if (typeof v === 'number' && !Number.isInteger(v)) return Number(v.toPrecision(5)).toString();
  return String(v);
}

function hover(r) {
  return C.map((name, j) => name + ': ' + fmt(r[j])).join('<br>');
}

function draw() {
  const shown = R.map((r, k) => k).filter(k => C.every((name, j) =>
    !(name in filters) || filters[name](R[k][j])));
  const groups = {};
  shown.forEach(k => { const c = category(R[k]); (groups[c] = groups[c] || []).push(k); });
  const order = [...D.classes, 'unclassified', 'failed'].filter(c => c in groups);
  const traces = order.map(c => ({
    type: 'scatter', mode: 'markers', name: c + ' (' + groups[c].length + ')',
    x: groups[c].map(k => xOf(R[k])), y: groups[c].map(k => R[k][col(yCol)]),
    customdata: groups[c], text: groups[c].map(k => hover(R[k])),
    hovertemplate: '%{text}<extra></extra>',
    marker: {color: D.styles[c].color, symbol: D.styles[c].symbol, size: 9,
             line: {color: '#000', width: 0.5}},
  }));
  const shapes = D.separatrix === null ? [] : [{type: 'line', xref: 'paper', x0: 0, x1: 1,
    y0: D.separatrix, y1: D.separatrix, line: {dash: 'dash', color: '#333', width: 1}}];
  Plotly.react('phase', traces, {
    margin: {l: 55, r: 10, t: 45, b: 40}, hovermode: 'closest', shapes: shapes,
    title: {text: (ARRAY ? 'displacement fraction f against length, by mode' :
      'phase diagram') + ': hover a run, click it for its trajectory' + (dodgeKey ?
      '<br><sub>runs of different ' + dodgeKey + ' side by side (' + dodgeVals.join(', ') +
      ', left to right)</sub>' : ''), font: {size: 13}, x: 0.01, xanchor: 'left'},
    xaxis: {title: {text: ARRAY ? 'L [µm]' : 'θ0 [deg]'}, tickvals: thetas},
    yaxis: {title: {text: ARRAY ? 'f (1: follows the tilt, 0: the flow)' : 'y0/h_obs'}},
    legend: {orientation: 'h', y: 1.0, yanchor: 'bottom', x: 1, xanchor: 'right'},
  }, {displaylogo: false, responsive: true});
  document.getElementById('count').textContent = shown.length + ' of ' + R.length + ' runs shown';
}

function pillarTrace(r, tr) {
  // channel: its one pillar; array: every pillar image around the path
  let xs = [], ys = [];
  if (!ARRAY) {
    const out = D.outlines[r[iSet]] || [];
    xs = out.map(p => p[0]).concat(out.length ? [out[0][0]] : []);
    ys = out.map(p => p[1]).concat(out.length ? [out[0][1]] : []);
  } else if (tr && D.lattices[r[iSet]]) {
    const L = D.lattices[r[iSet]], o = L.outline;
    const x0 = Math.min(...tr.x) - L.px, x1 = Math.max(...tr.x) + L.px;
    const y0 = Math.min(...tr.y) - 0.5 * L.py, y1 = Math.max(...tr.y) + 0.5 * L.py;
    for (let q = Math.floor(x0 / L.px); q <= Math.ceil(x1 / L.px); q++) {
      const dy = q * L.ls;
      for (let c = Math.floor((y0 - dy) / L.py); c <= Math.ceil((y1 - dy) / L.py); c++) {
        const ox = q * L.px, oy = dy + c * L.py;
        o.forEach(p => { xs.push(p[0] + ox); ys.push(p[1] + oy); });
        xs.push(o[0][0] + ox, null); ys.push(o[0][1] + oy, null);
      }
    }
  }
  return {type: 'scatter', mode: 'lines', name: ARRAY ? 'pillars' : 'pillar', fill: 'toself',
    x: xs, y: ys, line: {color: '#555'}, fillcolor: '#ddd', hoverinfo: 'skip'};
}

function showRun(k) {
  const r = R[k], id = r[iId], tr = D.tracks[id];
  const rows = C.map((name, j) => '<tr><td>' + name + '</td><td>' + fmt(r[j]) + '</td></tr>');
  document.getElementById('details').innerHTML = rows.join('');
  const traces = [pillarTrace(r, tr)];
  let title = 'run ' + id + ': θ0 = ' + fmt(r[col('theta0')]) + '°, ' + (ARRAY ?
    'y0 = ' + fmt(r[col('y0')]) + ' λy, L = ' + fmt(r[col('length')]) + ' µm, f = ' +
    fmt(r[col('fraction')]) : 'y0/h = ' + fmt(r[col('y0')]) + ', L/l_obs = ' +
    fmt(r[col('length')])) + ' → ' + category(r);
  let range;
  if (tr) {
    traces.push({type: 'scatter', mode: 'lines', name: 'centre of mass', x: tr.x, y: tr.y,
      line: {color: D.styles[category(r)] ? D.styles[category(r)].color : '#000', width: 2},
      text: tr.t.map(t => 't = ' + t + ' s'), hovertemplate: '%{text}<extra></extra>'});
    if (tr.fibers) {
      // the fiber at regular times: every bead of a flexible fiber, a rigid one's two ends
      const fx = [], fy = [], hx = [], hy = [];
      tr.fibers.forEach(f => {
        fx.push(...f[0], null); fy.push(...f[1], null);
        hx.push(f[0][f[0].length - 1]); hy.push(f[1][f[1].length - 1]);
      });
      const t0 = tr.t[0], t1 = tr.t[tr.t.length - 1];
      traces.push({type: 'scatter', mode: 'lines', name: 'fiber (' + tr.fibers.length +
        ' times)', x: fx, y: fy, line: {color: '#333', width: 2}, opacity: 0.6,
        hoverinfo: 'skip'});
      traces.push({type: 'scatter', mode: 'markers', name: 'head', hoverinfo: 'skip',
        x: hx, y: hy, marker: {color: tr.fiber_t, colorscale: 'Viridis', size: 6, cmin: t0,
        cmax: t1, colorbar: {title: {text: 't [s]'}, thickness: 10}}});
    } else if (tr.note) {
      title += ' (' + tr.note + ')';
    }
  } else {
    title += ' (no stored trajectory)';
  }
  if (!ARRAY) {
    const px = (D.outlines[r[iSet]] || []).map(p => p[0]);
    range = px.length ? [Math.min(...px) - 2.5, Math.max(...px) + 2.5] : undefined;
  }
  Plotly.react('traj', traces, {
    margin: {l: 55, r: 10, t: 30, b: 40},
    title: {text: title, font: {size: 13}, x: 0.01, xanchor: 'left'},
    xaxis: {title: {text: ARRAY ? 'x [µm] (flow →)' : 'x/h_obs (from the pillar centroid)'},
      range: range},
    yaxis: {title: {text: ARRAY ? 'y [µm]' : 'y/h_obs (from the base)'}, scaleanchor: 'x'},
    legend: {x: 0.01, y: 0.99, bgcolor: 'rgba(255,255,255,0.7)'},
  }, {displaylogo: false, responsive: true});
  document.getElementById('traj').dataset.run = id;
}

buildFilters();
draw();
Plotly.newPlot('traj', [], {title: {text: 'click a run to see its trajectory',
  font: {size: 13}}, margin: {l: 55, r: 10, t: 30, b: 40}, xaxis: {visible: false},
  yaxis: {visible: false}}, {displaylogo: false});
document.getElementById('phase').on('plotly_click', ev => showRun(ev.points[0].customdata));
"""
