"""The dashboard's style sheet and script (``html.py``), kept apart so the page's
structure reads on its own. Nothing is fetched: the page is one file."""

CSS = """
*{box-sizing:border-box}
body{font:14px/1.45 system-ui,sans-serif;margin:0 auto;padding:16px 20px;color:#222;
  background:#fafafa;max-width:1880px}
h1{font-size:22px;margin:4px 0}h2{font-size:18px;margin:26px 0 6px}h3{font-size:15px;margin:14px 0 4px}
#status{font-size:16px;font-weight:600;padding:8px 12px;border-radius:6px;margin:8px 0}
#status.ok{background:#e3f4e6;color:#176e2f;border:1px solid #9fd3aa}
#status.bad{background:#fde2e2;color:#b3261e;border:1px solid #f1a9a4}
.band{display:flex;flex-wrap:wrap;gap:8px;margin:8px 0}
.card{background:#fff;border:1px solid #ddd;border-radius:6px;padding:6px 12px;min-width:110px}
.card b{display:block;font-size:20px}.card.bad b{color:#b3261e}.card.ok b{color:#176e2f}
.card.warn b{color:#a35b00}.card small{color:#666;display:block;max-width:36em}
.filters{margin:10px 0;display:flex;flex-wrap:wrap;gap:6px;align-items:center}
.filters button{font:inherit;padding:3px 10px;border:1px solid #bbb;border-radius:14px;
  background:#fff;cursor:pointer}.filters button.on{background:#334;color:#fff;border-color:#334}
.scroll{overflow-x:auto;max-width:100%}
table{border-collapse:collapse;background:#fff;margin:6px 0;font-variant-numeric:tabular-nums}
th,td{border:1px solid #ddd;padding:3px 7px;text-align:left;vertical-align:top}
td{white-space:nowrap}td.id{white-space:normal;overflow-wrap:break-word;min-width:16em;max-width:30em}
td.wrap{white-space:normal;min-width:12em;max-width:30em}
th{background:#eef;cursor:pointer;user-select:none;white-space:nowrap}
th.asc:after{content:" \\25B2"}th.desc:after{content:" \\25BC"}
td.v{font-weight:600}
.s-passed,.s-pass,.s-better{color:#176e2f}.s-failed,.s-error,.s-crashed,.s-interrupted,
.s-broken,.s-fail,.s-regression{color:#b3261e}.s-xfailed,.s-xfail,.s-caught,.s-worse,
.s-xpassed{color:#a35b00}.s-skipped{color:#777}
tr.bad td{background:#fdf0ef}
.pics{display:flex;flex-wrap:wrap;gap:8px}
.pics figure{margin:0;flex:1 1 420px;max-width:640px}
.pics img{width:100%;border:1px solid #ddd;background:#fff}
.muted{color:#777}section.test{border-top:1px solid #ddd;padding-top:4px}
.hidden{display:none}
pre{background:#fff;border:1px solid #eee;padding:6px;overflow-x:auto;max-width:100%;font-size:12px}
"""

JS = """
function sortTable(table, col, dir){
  const body = table.tBodies[0]; const rows = Array.from(body.rows);
  const key = r => { const c = r.cells[col]; const v = c.dataset.sort;
    if (v !== undefined && v !== "") return parseFloat(v);
    return c.textContent.trim().toLowerCase(); };
  rows.sort((a, b) => { const x = key(a), y = key(b);
    const nx = typeof x === "number", ny = typeof y === "number";
    let r = nx && ny ? x - y : nx ? -1 : ny ? 1 : (x < y ? -1 : x > y ? 1 : 0);
    return dir === "desc" ? -r : r; });
  rows.forEach(r => body.appendChild(r));
  Array.from(table.tHead.rows[0].cells).forEach((th, i) => {
    th.classList.remove("asc", "desc"); if (i === col) th.classList.add(dir); });
  table.dataset.sorted = table.tHead.rows[0].cells[col].dataset.col + ":" + dir;
}
document.querySelectorAll("table.sortable").forEach(t => {
  Array.from(t.tHead.rows[0].cells).forEach((th, i) => th.addEventListener("click", () =>
    sortTable(t, i, th.classList.contains("asc") ? "desc" : "asc")));
});
function filterOutcome(o){
  document.querySelectorAll("[data-outcome]").forEach(el => {
    el.classList.toggle("hidden", o !== "all" && el.dataset.outcome !== o); });
  document.querySelectorAll(".filters button").forEach(b =>
    b.classList.toggle("on", b.dataset.filter === o));
  document.body.dataset.filter = o;
}
document.querySelectorAll(".filters button").forEach(b =>
  b.addEventListener("click", () => filterOutcome(b.dataset.filter)));
const m = location.hash.match(/^#sort=([\\w-]+):([^:]+):(asc|desc)$/);
if (m) { const t = document.getElementById(m[1]);
  if (t) { const ths = Array.from(t.tHead.rows[0].cells);
    const i = ths.findIndex(th => th.dataset.col === decodeURIComponent(m[2]));
    if (i >= 0) sortTable(t, i, m[3]); } }
const f = location.hash.match(/^#filter=(\\w+)$/);
if (f) filterOutcome(f[1]);
"""
