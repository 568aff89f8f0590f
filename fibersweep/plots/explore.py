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

from fibersweep.analysis.trajectory import CLASSES
from fibersweep.plots.style import CLASS_STYLE, FAILED_STYLE, UNCLASSIFIED_STYLE
from fibersweep.plots.tracks import _outline, normalised
from fibersweep.units import Geometry

__all__ = ["explorer_data", "explorer_html"]

#: Plotly marker symbols of the class markers (same shapes as the matplotlib figures).
_SYMBOLS = {"o": "circle", "s": "square", "^": "triangle-up", "D": "diamond", "P": "cross",
            "x": "x"}  # fmt: skip

#: Columns left out of the page (bookkeeping nobody filters by).
_HIDDEN = ("worker", "finished_at", "attempts", "cpu_time")


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


def explorer_data(
    runs: pd.DataFrame,
    samples: pd.DataFrame,
    geometries: Mapping[str, Geometry],
    *,
    separatrix: float | None = None,
    n_samples: int = 150,
) -> dict:
    """What the page needs, as plain JSON-able data.

    Parameters
    ----------
    runs : DataFrame
        The runs table.
    samples : DataFrame
        Trajectory rows of (some of) the runs.
    geometries : mapping of settings id -> Geometry
    separatrix : float, optional
        Far-upstream y/h_obs of the separatrix.
    n_samples : int
        Most points kept per trajectory (evenly spaced samples, the last kept).

    Returns
    -------
    dict
        ``columns``, ``rows`` (lists in column order), ``tracks`` (id -> t, x, y,
        head and tail in h_obs from the pillar's base centre), ``outlines``
        (settings id -> polygon), ``styles`` (class -> colour, symbol),
        ``separatrix``.
    """
    cols = [c for c in runs.columns if c not in _HIDDEN]
    rows = [[_jsonable(v) for v in r] for r in runs[cols].itertuples(index=False, name=None)]
    tracks = {}
    settings = runs.set_index("id")["settings"].astype(str).to_dict()
    for rid, s in samples.groupby("id", sort=False) if len(samples) else ():
        if rid not in settings or len(s) < 2:
            continue
        s = s.sort_values("sample")
        keep = np.unique(np.linspace(0, len(s) - 1, min(n_samples, len(s))).round().astype(int))
        p = normalised(s.iloc[keep], geometries[settings[rid]])
        tr = {k: np.round(v, 4).tolist() for k, v in p.items()}
        tr["t"] = np.round(s["t"].to_numpy(dtype=float)[keep], 4).tolist()
        tracks[str(rid)] = tr
    styles = {c: {"color": st["color"], "symbol": _SYMBOLS[str(st["marker"])]}
              for c, st in CLASS_STYLE.items()}  # fmt: skip
    styles["unclassified"] = {"color": UNCLASSIFIED_STYLE["color"], "symbol": "cross"}
    styles["failed"] = {"color": FAILED_STYLE["color"], "symbol": "x"}
    sep = float(separatrix) if separatrix is not None and math.isfinite(separatrix) else None
    return {
        "columns": cols,
        "rows": rows,
        "tracks": tracks,
        "outlines": {sid: np.round(_outline(g), 4).tolist() for sid, g in geometries.items()},
        "styles": styles,
        "classes": list(CLASSES),
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
) -> str:
    """The whole page as one string (plotly.js and the data inlined; no network access).

    Parameters as :func:`explorer_data` (``samples_per_run`` is its ``n_samples``);
    ``title`` names the folder on the page.
    """
    from plotly.offline import get_plotlyjs

    data = explorer_data(runs, samples, geometries, separatrix=separatrix,
                         n_samples=samples_per_run)  # fmt: skip
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
const iClass = col('class'), iStatus = col('status'), iId = col('id');
const iSet = col('settings');
const filters = {};   // column -> function(value) -> bool
// runs that differ only in a setting (length, a swept key) would sit on one point:
// set them side by side along θ0 by the first such setting that varies
const dodgeKey = C.filter(c => c.includes('.')).concat(['length']).find(c =>
  col(c) >= 0 && new Set(R.map(r => r[col(c)])).size > 1);
const dodgeVals = dodgeKey ? [...new Set(R.map(r => r[col(dodgeKey)]))].sort(
  (a, b) => (a < b ? -1 : a > b ? 1 : 0)) : [null];
const thetas = [...new Set(R.map(r => r[col('theta0')]))].sort((a, b) => a - b);
const dTheta = thetas.length > 1 ? Math.min(...thetas.slice(1).map((v, j) => v - thetas[j])) : 1;
function xOf(r) {
  if (!dodgeKey) return r[col('theta0')];
  const j = dodgeVals.indexOf(r[col(dodgeKey)]), n = dodgeVals.length;
  return r[col('theta0')] + (j - (n - 1) / 2) * 0.6 * dTheta / n;
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
    x: groups[c].map(k => xOf(R[k])), y: groups[c].map(k => R[k][col('y0')]),
    customdata: groups[c], text: groups[c].map(k => hover(R[k])),
    hovertemplate: '%{text}<extra></extra>',
    marker: {color: D.styles[c].color, symbol: D.styles[c].symbol, size: 9,
             line: {color: '#000', width: 0.5}},
  }));
  const shapes = D.separatrix === null ? [] : [{type: 'line', xref: 'paper', x0: 0, x1: 1,
    y0: D.separatrix, y1: D.separatrix, line: {dash: 'dash', color: '#333', width: 1}}];
  Plotly.react('phase', traces, {
    margin: {l: 55, r: 10, t: 45, b: 40}, hovermode: 'closest', shapes: shapes,
    title: {text: 'phase diagram: hover a run, click it for its trajectory' + (dodgeKey ?
      '<br><sub>runs of different ' + dodgeKey + ' side by side (' + dodgeVals.join(', ') +
      ', left to right)</sub>' : ''), font: {size: 13}, x: 0.01, xanchor: 'left'},
    xaxis: {title: {text: 'θ0 [deg]'}, tickvals: thetas}, yaxis: {title: {text: 'y0/h_obs'}},
    legend: {orientation: 'h', y: 1.0, yanchor: 'bottom', x: 1, xanchor: 'right'},
  }, {displaylogo: false, responsive: true});
  document.getElementById('count').textContent = shown.length + ' of ' + R.length + ' runs shown';
}

function showRun(k) {
  const r = R[k], id = r[iId], tr = D.tracks[id];
  const rows = C.map((name, j) => '<tr><td>' + name + '</td><td>' + fmt(r[j]) + '</td></tr>');
  document.getElementById('details').innerHTML = rows.join('');
  const out = D.outlines[r[iSet]] || [];
  const traces = [{type: 'scatter', mode: 'lines', name: 'pillar', fill: 'toself',
    x: out.map(p => p[0]).concat(out.length ? [out[0][0]] : []),
    y: out.map(p => p[1]).concat(out.length ? [out[0][1]] : []),
    line: {color: '#555'}, fillcolor: '#ddd', hoverinfo: 'skip'}];
  let title = 'run ' + id + ': θ0 = ' + fmt(r[col('theta0')]) + '°, y0/h = ' +
    fmt(r[col('y0')]) + ', L/l_obs = ' + fmt(r[col('length')]) + ' → ' + category(r);
  if (tr) {
    traces.push({type: 'scatter', mode: 'lines', name: 'centre of mass', x: tr.x, y: tr.y,
      line: {color: D.styles[category(r)] ? D.styles[category(r)].color : '#000', width: 2},
      text: tr.t.map(t => 't = ' + t + ' s'), hovertemplate: '%{text}<extra></extra>'});
    // the fiber drawn at regular samples while it is near the pillar (within the window)
    const px = out.map(p => p[0]), lo = Math.min(...px) - 2, hi = Math.max(...px) + 2;
    let near = tr.x.map((x, i) => i).filter(i => tr.x[i] > lo && tr.x[i] < hi);
    if (near.length < 2) near = tr.x.map((x, i) => i);
    const n = near.length, m = Math.min(16, n), t0 = tr.t[0], t1 = tr.t[tr.t.length - 1];
    const fx = [], fy = [], fc = [];
    for (let q = 0; q < m; q++) {
      const i = near[Math.round(q * (n - 1) / Math.max(m - 1, 1))];
      fx.push(tr.tail_x[i], tr.head_x[i], null); fy.push(tr.tail_y[i], tr.head_y[i], null);
      fc.push(tr.t[i]);
    }
    traces.push({type: 'scatter', mode: 'lines', name: 'fiber (' + m + ' times)', x: fx, y: fy,
      line: {color: '#333', width: 2}, opacity: 0.6, hoverinfo: 'skip'});
    traces.push({type: 'scatter', mode: 'markers', name: 'head', hoverinfo: 'skip',
      x: fx.filter((v, j) => j % 3 === 1), y: fy.filter((v, j) => j % 3 === 1),
      marker: {color: fc, colorscale: 'Viridis', size: 6, cmin: t0, cmax: t1,
               colorbar: {title: {text: 't [s]'}, thickness: 10}}});
  } else {
    title += ' (no stored trajectory)';
  }
  const px = out.map(p => p[0]);
  const range = px.length ? [Math.min(...px) - 2.5, Math.max(...px) + 2.5] : undefined;
  Plotly.react('traj', traces, {
    margin: {l: 55, r: 10, t: 30, b: 40},
    title: {text: title, font: {size: 13}, x: 0.01, xanchor: 'left'},
    xaxis: {title: {text: 'x/h_obs (from the pillar centroid)'}, range: range},
    yaxis: {title: {text: 'y/h_obs (from the base)'}, scaleanchor: 'x'},
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
