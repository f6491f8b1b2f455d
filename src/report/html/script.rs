//! The page's style and its two small scripts: the error report (first, in the head) and the
//! player (last): it moves every shape with `data-p` to the frame the slider names, plays the
//! frames back and forth, and sets `data-ready="1"` on the body once the first frame is drawn.
//! A script error sets `data-error` on the body (or the root element) with its message.

/// The style sheet.
pub(super) const CSS: &str = "
body{font:14px/1.4 system-ui,sans-serif;margin:1.5em;color:#222;max-width:1150px}
h1{font-size:1.4em}h2{font-size:1.15em;margin-top:1.6em;border-bottom:1px solid #ccc}
table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #ccc;padding:2px 6px;text-align:left;vertical-align:top}
table.groups td{font-family:monospace;font-size:12px}
.none{color:#666;font-style:italic}.legend{color:#444;font-size:12px}
#status.ok{color:#1e7b34}#status.over{color:#b03a2e}#status.under,#status.mixed{color:#9a6700}
ul.diagnosis li{margin:.3em 0}
svg.view{display:block;border:1px solid #ddd;background:#fff;max-width:100%;height:auto}
svg text{font:12px monospace;text-anchor:middle;fill:#222}svg text.name{font-weight:bold}
#diagram rect{fill:#fff;stroke:#333}#diagram .frame rect{fill:#ddd}
#diagram .uncovered rect{fill:#fff3c4}#diagram .under rect{fill:#f9d68a;stroke:#9a6700}
#diagram .over rect{fill:#f4a6a6;stroke:#b03a2e}#diagram .part rect{stroke-dasharray:5 3}
#diagram .edge{stroke:#555;stroke-width:1.2}
#rigid .part>rect{fill:#fafafa;stroke:#888;stroke-dasharray:5 3}#rigid .framed>rect{fill:#eee}
#rigid .alone>rect{stroke:#ccc}#rigid text.ptitle{text-anchor:start;font-size:11px;fill:#666}
#rigid .body rect{fill:#fff;stroke:#333}#rigid .body.frame rect{fill:#ddd}
#rigid .body.isolated rect{stroke:#b03a2e;stroke-width:3}
.key{display:inline-block;width:1em;height:.8em;border:1px solid #333;vertical-align:middle}
.key.over{background:#f4a6a6}.key.under{background:#f9d68a}.key.uncovered{background:#fff3c4}
.key.framed{background:#eee}.key.isolated{border:3px solid #b03a2e}
#mechanism .link{fill:#4a7fb5;fill-opacity:.18;stroke:#2c5d8f;stroke-width:2.5;stroke-linejoin:round}
#mechanism .link.frame{fill:#999;stroke:#666}
#mechanism .axis{stroke:#555;stroke-width:1.5}
#mechanism .joint{fill:#fff;stroke:#222;stroke-width:1.5}#mechanism .joint.driven{fill:#2c5d8f}
#mechanism .joint.under{fill:#f9d68a;stroke:#9a6700;stroke-width:2.5}
#mechanism .joint.redundant{stroke:#b03a2e;stroke-width:2.5}#mechanism .joint.over{fill:#f4a6a6;stroke:#b03a2e;stroke-width:2.5}
.controls{margin:.5em 0}.controls input{width:420px;vertical-align:middle}
";

/// Script errors into the DOM.
pub(super) const ON_ERROR: &str = "window.onerror=function(m,s,l){var e=document.body||document.documentElement;e.setAttribute('data-error',String(m)+' at line '+l);};";

/// The player.
pub(super) const MAIN: &str = "
(function(){
var d=document.getElementById('frames');
if(!d){document.body.setAttribute('data-ready','1');return;}
var F=JSON.parse(d.textContent),S=document.getElementById('step'),L=document.getElementById('step-label'),B=document.getElementById('play');
var shapes=document.querySelectorAll('#mechanism [data-p]');
var V=(S.getAttribute('data-values')||'').split(' ');
function draw(k){var f=F[k];
for(var i=0;i<shapes.length;i++){var e=shapes[i],p=e.getAttribute('data-p').split(' ');
if(e.tagName==='circle'){e.setAttribute('cx',f[2*p[0]]);e.setAttribute('cy',f[2*p[0]+1]);}
else if(e.tagName==='line'){e.setAttribute('x1',f[2*p[0]]);e.setAttribute('y1',f[2*p[0]+1]);e.setAttribute('x2',f[2*p[1]]);e.setAttribute('y2',f[2*p[1]+1]);}
else{var q=[];for(var j=0;j<p.length;j++)q.push(f[2*p[j]]+','+f[2*p[j]+1]);e.setAttribute('points',q.join(' '));}}
L.textContent='frame '+(k+1)+' of '+F.length+(V[k]?' (value '+V[k]+')':'');}
var t=null,dir=1;
S.addEventListener('input',function(){draw(+S.value);});
B.addEventListener('click',function(){if(t){clearInterval(t);t=null;B.textContent='play';return;}
B.textContent='pause';t=setInterval(function(){var k=+S.value+dir;if(k>=F.length||k<0){dir=-dir;k=+S.value+dir;}
if(k<0||k>=F.length)k=0;S.value=k;draw(k);},80);});
draw(0);
document.body.setAttribute('data-frames-drawn',String(F.length));
document.body.setAttribute('data-ready','1');
})();
";
