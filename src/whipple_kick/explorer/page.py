"""The explorer's page: one HTML document with its style and script inline, nothing loaded from elsewhere.

The form comes from :func:`whipple_kick.explorer.form.fields`; the figures are the PNGs the project's
figure modules draw (``simulate``'s response.png, ``compare``'s compare.png, ``stability``'s
stability.png) and the animation the GIF of :func:`whipple_kick.figures.animation.animate`, so what the
page shows is what the commands write. The script (plain JavaScript, no library) sends the form, shows the
progress and the outcome, keeps the list of runs, and asks for the overlay, the animation, the stability and
the P(best). Element ids are the page's interface for the browser tests (tests/explorer).
"""
import html

from whipple_kick import __version__

#: Most runs overlaid in one figure (the issue's "up to four").
MAX_OVERLAID = 4

_STYLE = """
body { font-family: sans-serif; margin: 1em 2em; color: #222; }
h1 { font-size: 1.4em; margin-bottom: 0.2em; }
.lead { color: #555; margin-top: 0; }
.columns { display: flex; gap: 2em; align-items: flex-start; }
form { flex: 0 0 23em; }
section#results { flex: 1 1 auto; min-width: 0; }
.field { margin: 0.45em 0; }
.field label { display: block; font-weight: bold; font-size: 0.9em; }
.field input[type=text], .field select { width: 14em; }
.range { color: #666; font-size: 0.8em; margin-left: 0.4em; }
.error { color: #b00020; font-size: 0.85em; }
.error:empty { display: none; }
button { margin: 0.6em 0.4em 0 0; padding: 0.3em 1em; }
#status { font-size: 0.9em; color: #444; }
img.figure { max-width: 100%; border: 1px solid #ddd; }
#summary li { margin: 0.2em 0; }
#runs li { margin: 0.3em 0; }
.fell { color: #b00020; font-weight: bold; }
table { border-collapse: collapse; font-size: 0.9em; }
td, th { border: 1px solid #ccc; padding: 0.2em 0.6em; text-align: right; }
pre { font-size: 0.85em; white-space: pre-wrap; }
"""

_SCRIPT = """
const MAX = __MAX__;
const form = document.getElementById('scenario');
const runs = [];
function $(id) { return document.getElementById(id); }
function clearErrors() { document.querySelectorAll('.error').forEach(e => { e.textContent = ''; }); }
function showErrors(errors) {
  for (const [name, text] of Object.entries(errors)) {
    const box = $('error-' + name) || $('error-form');
    box.textContent = text;
  }
}
async function busy(label, work) {
  const progress = $('progress'), status = $('status');
  const started = performance.now();
  progress.hidden = false;
  status.textContent = label + '...';
  const timer = setInterval(() => {
    status.textContent = label + '... ' + ((performance.now() - started) / 1000).toFixed(1) + ' s';
  }, 100);
  try { return await work(); }
  catch (err) { $('error-form').textContent = 'request failed: ' + err; return null; }
  finally { clearInterval(timer); progress.hidden = true; status.textContent = ''; }
}
async function post(url, body) {
  const response = await fetch(url, {method: 'POST', body: body});
  return await response.json();
}
form.addEventListener('submit', async (event) => {
  event.preventDefault();
  clearErrors();
  const reply = await busy('running', () => post('/run', new FormData(form)));
  if (!reply) return;
  if (reply.errors) { showErrors(reply.errors); return; }
  const run = reply.run;
  run.number = runs.length + 1;   // the runs of this page, numbered as the page shows them
  const summary = $('summary');
  summary.innerHTML = '';
  run.words.forEach((sentence, k) => {
    const li = document.createElement('li');
    li.textContent = sentence;
    if (k === 0 && run.outcome !== 'completed') li.className = 'fell';
    summary.appendChild(li);
  });
  $('summary-title').textContent = 'Run ' + run.number + ': ' + run.label;
  if (run.figure_url) { $('figure').src = run.figure_url; $('figure').hidden = false; }
  else { $('figure').hidden = true; }
  runs.push(run);
  addRun(run);
  refreshOverlay();
  refreshPBest();
});
function addRun(run) {
  const li = document.createElement('li');
  li.id = 'run-' + run.number;
  const box = document.createElement('input');
  box.type = 'checkbox';
  box.className = 'overlay-choice';
  box.value = run.id;
  box.dataset.number = run.number;
  box.title = 'overlay this run (at most ' + MAX + ')';
  box.checked = document.querySelectorAll('.overlay-choice:checked').length < MAX;
  box.addEventListener('change', () => { limitChoices(); refreshOverlay(); });
  li.appendChild(box);
  const text = document.createElement('span');
  text.textContent = ' ' + run.number + ': ' + run.label + ' -- ' + run.words[0] + ' ';
  li.appendChild(text);
  const link = document.createElement('a');
  link.href = run.download_url;
  link.className = 'download';
  link.textContent = 'download run folder';
  li.appendChild(link);
  if (run.figure_url) {
    const animate = document.createElement('button');
    animate.type = 'button';
    animate.className = 'animate';
    animate.textContent = 'animate';
    animate.addEventListener('click', () => makeAnimation(run));
    li.appendChild(animate);
  }
  $('runs').appendChild(li);
  limitChoices();
}
function limitChoices() {
  const boxes = document.querySelectorAll('.overlay-choice');
  const full = document.querySelectorAll('.overlay-choice:checked').length >= MAX;
  boxes.forEach(b => { b.disabled = full && !b.checked; });
}
async function refreshOverlay() {
  const ticked = Array.from(document.querySelectorAll('.overlay-choice:checked'));
  const ids = ticked.map(b => b.value), numbers = ticked.map(b => Number(b.dataset.number));
  const img = $('overlay');
  if (ids.length < 2) { img.hidden = true; img.removeAttribute('src'); return; }
  const reply = await busy('overlaying ' + ids.length + ' runs', () => post('/overlay', JSON.stringify({ids: ids, numbers: numbers})));
  if (reply && reply.url) { img.src = reply.url; img.hidden = false; }
  else if (reply && reply.error) { $('error-form').textContent = reply.error; }
}
async function makeAnimation(run) {
  const reply = await busy('animating run ' + run.number, () => post('/animate/' + run.id, ''));
  if (reply && reply.url) { $('animation').src = reply.url; $('animation').hidden = false; }
  else if (reply && reply.error) { $('error-form').textContent = reply.error; }
}
$('stability-button').addEventListener('click', async () => {
  clearErrors();
  const reply = await busy('stability against speed', () => post('/stability', new FormData(form)));
  if (!reply) return;
  if (reply.errors) { showErrors(reply.errors); return; }
  $('stability-lines').textContent = reply.lines.join('\\n');
  $('stability-figure').src = reply.url;
  $('stability-figure').hidden = false;
});
async function refreshPBest() {
  const box = $('pbest');
  const load = $('field-fz_n').value;
  const response = await fetch('/pbest?fz_n=' + encodeURIComponent(load));
  const reply = await response.json();
  if (reply.error) { box.textContent = reply.error; return; }
  if (!reply.text) { box.innerHTML = ''; box.textContent = reply.note; return; }
  box.innerHTML = '';
  const note = document.createElement('p');
  note.textContent = reply.note;
  box.appendChild(note);
  for (const [criterion, rows] of Object.entries(reply.rows)) {
    const table = document.createElement('table');
    const head = table.insertRow();
    ['P(best), ' + criterion, 'P', '95 % interval'].forEach(t => {
      const th = document.createElement('th'); th.textContent = t; head.appendChild(th);
    });
    rows.forEach(r => {
      const row = table.insertRow();
      [r.pressure + (r.measured_best ? ' (measured best)' : ''), r.p.toFixed(2),
       '[' + r.low.toFixed(2) + ', ' + r.high.toFixed(2) + ']'].forEach(t => { row.insertCell().textContent = t; });
    });
    box.appendChild(table);
  }
}
$('field-fz_n').addEventListener('change', refreshPBest);
refreshPBest();
"""


def _field_html(field):
    """One field: label with unit, input or select, the declared range, and the box for its message."""
    e = html.escape
    unit = f" [{e(field.unit)}]" if field.unit else ""
    attrs = f'id="field-{e(field.name)}" name="{e(field.name)}" title="{e(field.help)}"'
    if field.choices:
        options = "".join(f'<option value="{e(c)}"{" selected" if c == field.value else ""}>{e(c)}</option>'
                          for c in field.choices)
        control = f"<select {attrs}>{options}</select>"
    else:
        listed = f' list="list-{e(field.name)}"' if field.suggestions else ""
        control = (f'<input type="text" {attrs} value="{e(field.value)}" placeholder="{e(field.placeholder)}"'
                   f'{listed} spellcheck="false">')
        if field.suggestions:
            control += (f'<datalist id="list-{e(field.name)}">'
                        + "".join(f'<option value="{e(s)}">' for s in field.suggestions) + "</datalist>")
    extra = ""
    if field.name == "bicycle":
        extra = ('<br><label for="field-bicycle_file" class="range">or a BicycleParameters file '
                 '(&lt;Name&gt;Benchmark.txt):</label> <input type="file" id="field-bicycle_file" '
                 'name="bicycle_file" accept=".txt">')
    span = f'<span class="range">{e(field.range_text)}</span>' if field.range_text else ""
    return (f'<div class="field"><label for="field-{e(field.name)}">{e(field.label)}{unit}</label>{control}{span}'
            f'{extra}<div class="error" id="error-{e(field.name)}"></div></div>')


def render(fields, study=None):
    """The page's HTML: the form of ``fields`` (:func:`whipple_kick.explorer.form.fields`) and the result panes.

    ``study`` names the uncertainty study's folder the page reads P(best) from (None: none given).
    """
    e = html.escape
    study_text = (f"from the uncertainty study in {e(str(study))}" if study is not None else
                  "none: start the explorer with --study DIR (a folder holding p_best.csv)")
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>whipple_kick kick explorer</title>
<link rel="icon" href="data:,">
<style>{_STYLE}</style></head>
<body>
<h1>Kick explorer</h1>
<p class="lead">whipple_kick {e(__version__)}: a kick-plate run of the bicycle-rider model, as <code>simulate</code>
makes it. Every field keeps <code>simulate</code>'s default unless changed; hover a field for its meaning.</p>
<div class="columns">
<form id="scenario" enctype="multipart/form-data">
{"".join(_field_html(f) for f in fields)}
<div class="error" id="error-form"></div>
<button type="submit" id="run">Run</button><button type="button" id="stability-button">Stability against speed</button>
<div><progress id="progress" hidden></progress> <span id="status"></span></div>
</form>
<section id="results">
<h2 id="summary-title">No run yet</h2>
<ul id="summary"></ul>
<img id="figure" class="figure" alt="response of the last run" hidden>
<h2>Runs</h2>
<p class="lead">Tick up to {MAX_OVERLAID} runs to overlay them; each run's folder holds the files
<code>simulate</code> writes (<code>compare</code> and <code>Result.load</code> read it).</p>
<ol id="runs"></ol>
<img id="overlay" class="figure" alt="the ticked runs overlaid" hidden>
<img id="animation" class="figure" alt="animation of a run" hidden>
<h2>Stability against speed</h2>
<pre id="stability-lines"></pre>
<img id="stability-figure" class="figure" alt="eigenvalues against speed" hidden>
<h2>P(best) at this load</h2>
<p class="lead">The probability that each pressure recovers fastest, {study_text}.</p>
<div id="pbest"></div>
</section>
</div>
<script>{_SCRIPT.replace("__MAX__", str(MAX_OVERLAID))}</script>
</body></html>
"""
