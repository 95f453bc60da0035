"""The ML gallery of the dashboard: a detection task's worst frames with their boxes.

``pictures(flight, result)``: the flight's gallery entries (``result.ml_gallery``,
drawn by ``ml.gallery.worst_frames``) as dashboard pictures, each with a
``gallery`` caption; ``figure(picture, key)``: the HTML of one, the PNG with a
legend and a table of its objects (kind, class, box, score, visible fraction)
under the frame's time, file, altitude and blur.
"""

from __future__ import annotations

import html as _html

#: legend text by box kind (the colours are ml.gallery.COLOURS)
LEGEND = (("tp", "#28c83c", "found"), ("fp", "#e62828", "false positive"),
          ("miss", "#ff9600", "missed"), ("ignore", "#969696", "ignore region"))


def _e(x) -> str:
    return _html.escape(str(x), quote=True)


def pictures(flight: str, result) -> list[dict]:
    """Dashboard pictures of the worst frames of each detection task of ``result``."""
    out = []
    for task, frames in (getattr(result, "ml_gallery", None) or {}).items():
        for rank, f in enumerate(frames, 1):
            if not f.get("png"):
                continue
            cap = {k: v for k, v in f.items() if k != "png"}
            out.append({"title": f"{flight}: {task} worst frame {rank} (frame {f['index']})",
                        "data": f["png"], "mime": "image/png",
                        "gallery": {"task": task, "rank": rank, **cap}})
    return out


def figure(p: dict, key: str) -> str:
    """One gallery picture as a <figure class="ml-frame"> with its caption table."""
    g = p["gallery"]
    rows = "".join(
        f'<tr class="{_e(o["kind"])}"><td>{_e(o["kind"])}</td><td>{_e(o["class"])}</td>'
        f'<td>{_e(", ".join(f"{v:g}" for v in o["box"]))}</td><td>{_e(o.get("score", ""))}</td>'
        f'<td>{_e(o.get("visible", ""))}</td></tr>' for o in g["objects"])
    legend = " ".join(f'<span style="color:{c}">&#9632; {_e(t)}</span>' for _, c, t in LEGEND)
    facts = (f'frame {g["index"]}' + (f' · {_e(g["file"])}' if g.get("file") else "")
             + f' · t {g["t"]:.2f} s · altitude {g["altitude_m"]:.1f} m · blur {g["blur_px"]:.2f} px')
    return (f'<figure id="pic-{key}" class="ml-frame" data-task="{_e(g["task"])}" '
            f'data-frame="{g["index"]}" data-file="{_e(g.get("file") or "")}" '
            f'data-scale="{g["scale"]}"><img alt="{_e(p["title"])}" '
            f'src="data:{_e(p.get("mime", "image/png"))};base64,{p["data"]}">'
            f'<figcaption class="muted">{_e(p["title"])}<br>{facts}<br>{legend}'
            f'<table class="ml-objects"><thead><tr><th>kind</th><th>class</th><th>box (px)</th>'
            f'<th>score</th><th>visible</th></tr></thead><tbody>{rows}</tbody></table>'
            f'</figcaption></figure>')
