(function () {
"use strict";
var data = JSON.parse(document.getElementById("meshcol-data").textContent);
var THREE = MeshCat.THREE;
var units = data.units ? " " + data.units : "";
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
viewer.renderer.setPixelRatio(1);
var cmd = function (c) { viewer.handle_command(c); };
cmd({type: "set_property", path: "/Background", property: "top_color", value: [1, 1, 1]});
cmd({type: "set_property", path: "/Background", property: "bottom_color", value: [0.85, 0.85, 0.87]});
cmd({type: "set_property", path: "/Grid", property: "visible", value: false});
cmd({type: "set_property", path: "/Axes", property: "visible", value: false});

function decode(text, Kind) {
  var raw = atob(text), bytes = new Uint8Array(raw.length);
  for (var i = 0; i < raw.length; i++) bytes[i] = raw.charCodeAt(i);
  return new Kind(bytes.buffer);
}
var colorInt = function (hex) { return parseInt(hex.slice(1), 16); };
var uid = 0;
var id = function () { uid += 1; return "meshcol-" + uid; };
function objectJson(type, geometry, material, matrix) {
  var g = id(), m = id();
  geometry.uuid = g; material.uuid = m;
  return {metadata: {version: 4.5, type: "Object"}, geometries: [geometry], materials: [material],
          object: {uuid: id(), type: type, geometry: g, material: m,
                   matrix: matrix || [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]}};
}
function material(type, color, opacity, extra) {
  var m = {type: type, color: colorInt(color), side: 2, transparent: opacity < 1,
           opacity: opacity, depthWrite: opacity >= 1};
  for (var k in extra || {}) m[k] = extra[k];
  return m;
}
var positions = data.geometries.map(function (g) { return decode(g.p, Float32Array); });
var indices = data.geometries.map(function (g) { return decode(g.i, Uint32Array); });
var byBody = {};  // body index -> list of THREE objects
var paths = [];
function place(path, json, body) {
  cmd({type: "set_object", path: path, object: json});
  var node = viewer.scene_tree.find(path.split("/").filter(Boolean).concat(["<object>"]));
  var obj = node.object;
  obj.castShadow = false; obj.receiveShadow = false;
  if (body >= 0) { (byBody[body] = byBody[body] || []).push(obj); }
  paths.push(path);
  return obj;
}
data.objects.forEach(function (o, k) {
  var geometry = {type: "BufferGeometry", data: {
    attributes: {position: {itemSize: 3, type: "Float32Array", array: positions[o.g],
                            normalized: false}},
    index: {type: "Uint32Array", array: indices[o.g]}}};
  // translucent overlays drawn a hair in front of the surface they cover (no z-fighting)
  var mat = material("MeshPhongMaterial", o.color, o.opacity,
                     {wireframe: o.wire, shininess: 10, flatShading: true,
                      polygonOffset: o.opacity < 1 || o.group !== "meshes",
                      polygonOffsetFactor: -1, polygonOffsetUnits: -1});
  var obj = place("/meshcol/" + o.group + "/" + k, objectJson("Mesh", geometry, mat, o.m), o.body);
  obj.userData.baseColor = colorInt(o.color);
  if (o.opacity < 1) obj.renderOrder = 1;
});
data.lines.forEach(function (l, k) {
  var geometry = {type: "BufferGeometry", data: {attributes: {position: {itemSize: 3,
    type: "Float32Array", array: decode(l.p, Float32Array), normalized: false}}}};
  place("/meshcol/" + l.group + "/lines" + k,
        objectJson("LineSegments", geometry, material("LineBasicMaterial", l.color, 1)), l.body);
});
var pointSize = Math.max(data.radius * 0.012, 1e-9);
data.points.forEach(function (p, k) {
  var geometry = {type: "BufferGeometry", data: {attributes: {position: {itemSize: 3,
    type: "Float32Array", array: decode(p.p, Float32Array), normalized: false}}}};
  place("/meshcol/" + p.group + "/points" + k, objectJson("Points", geometry,
        material("PointsMaterial", p.color, 1, {size: 7, sizeAttenuation: false})), -1);
});

// legend: one toggle per group
var legend = document.getElementById("legend");
Object.keys(data.groups).forEach(function (name) {
  var g = data.groups[name];
  var row = document.createElement("label");
  row.style.display = "block";
  var box = document.createElement("input");
  box.type = "checkbox"; box.checked = g.visible; box.dataset.group = name;
  box.onchange = function () {
    cmd({type: "set_property", path: "/meshcol/" + name, property: "visible", value: box.checked});
  };
  if (!g.visible) box.onchange();
  row.appendChild(box);
  row.insertAdjacentHTML("beforeend", '<span class="swatch" style="background:' + g.color +
                         '"></span>');
  row.appendChild(document.createTextNode(g.label));
  legend.appendChild(row);
});

// side panel
document.getElementById("heading").textContent = "meshcol " + data.command + ": " + data.title;
var info = document.getElementById("info");
data.info.forEach(function (kv) {
  var tr = info.insertRow(); tr.insertCell().textContent = kv[0];
  tr.insertCell().textContent = kv[1];
});
var unitsRow = info.insertRow(); unitsRow.insertCell().textContent = "units";
unitsRow.insertCell().textContent = data.units || "(not declared)";
data.notes.forEach(function (text) {
  var div = document.createElement("div"); div.className = "note"; div.textContent = text;
  document.getElementById("notes").appendChild(div);
});

// camera: frame a box (world), keeping the view direction
function frame(box) {
  var centre = box.getCenter(new THREE.Vector3());
  var r = Math.max(box.getSize(new THREE.Vector3()).length() * 0.5, data.radius * 1e-6, 1e-9);
  var cam = viewer.camera, parent = cam.parent;
  parent.updateMatrixWorld(true);
  var target = parent.worldToLocal(centre.clone());
  var dir = cam.position.clone().sub(viewer.controls.target);
  if (dir.lengthSq() === 0 || !isFinite(dir.lengthSq())) dir.set(1, 0.6, 1);
  dir.normalize();
  var distance = r / Math.sin(cam.fov * Math.PI / 360) * 1.1;
  viewer.controls.target.copy(target);
  cam.position.copy(target).add(dir.multiplyScalar(distance));
  cam.near = Math.max(distance - 3 * r, distance * 1e-4, 1e-12) * 0.5;
  cam.far = distance + 3 * data.radius + 3 * r;
  cam.updateProjectionMatrix();
  viewer.controls.update();
  viewer.set_dirty();
}
viewer.camera.position.set(1.5, 1.0, 1.5);
viewer.controls.target.set(0, 0, 0);
viewer.scene.updateMatrixWorld(true);
var whole = new THREE.Box3(new THREE.Vector3().fromArray(data.extent).negate(),
                           new THREE.Vector3().fromArray(data.extent))
  .applyMatrix4(viewer.scene.matrixWorld);
frame(whole);
viewer.controls.minDistance = 0;
viewer.controls.maxDistance = Infinity;

// the table; choosing a row frames and highlights its bodies
var head = document.getElementById("head"), rowsEl = document.getElementById("rows");
document.getElementById("tabletitle").textContent = data.table.title;
if (data.table.columns.length) {
  var hr = head.insertRow();
  ["#"].concat(data.table.columns).forEach(function (c) {
    var th = document.createElement("th"); th.textContent = c; hr.appendChild(th);
  });
}
var trs = [];
data.table.rows.forEach(function (row, i) {
  var tr = rowsEl.insertRow();
  if (row.severity === "violation") tr.className = "violation";
  [i].concat(row.cells).forEach(function (c) {
    var td = tr.insertCell(); td.textContent = c; td.title = c;  // cut cells show it whole
  });
  tr.onclick = function () { location.hash = "pair=" + i; };
  trs.push(tr);
});
var marks = null, chosen = -1, labelPoint = null, label = document.getElementById("label");
var rowGroups = {};
data.table.rows.forEach(function (r) { if (r.group) rowGroups[r.group] = true; });
function setGroup(name, visible) {
  cmd({type: "set_property", path: "/meshcol/" + name, property: "visible", value: visible});
}
Object.keys(rowGroups).forEach(function (g) { setGroup(g, false); });
// Pages of single bodies (inspect, hull, decompose): a chosen body is shown alone, so that a
// body inside another is not hidden by it; pair pages keep every body for context.
var isolate = data.command !== "check" && data.command !== "sweep";
function showOthers(row, visible) {
  if (!isolate) return;
  Object.keys(byBody).forEach(function (b) {
    if (row.bodies.indexOf(parseInt(b, 10)) >= 0) return;
    byBody[b].forEach(function (o) { o.visible = visible; });
  });
}
function choose(i) {
  if (i === chosen) return;
  if (chosen >= 0) {
    var before = data.table.rows[chosen];
    trs[chosen].classList.remove("chosen");
    before.bodies.forEach(function (b) {
      (byBody[b] || []).forEach(function (o) {
        if (o.material.color && o.userData.baseColor !== undefined)
          o.material.color.setHex(o.userData.baseColor);
        if (o.material.emissive) o.material.emissive.setHex(0);
      });
    });
    if (before.group) setGroup(before.group, false);
    showOthers(before, true);
  }
  if (marks) { viewer.scene.remove(marks); marks = null; }
  chosen = i; labelPoint = null; label.style.display = "none";
  if (i < 0 || i >= data.table.rows.length) { chosen = -1; frame(whole); return; }
  var row = data.table.rows[i];
  trs[i].classList.add("chosen");
  trs[i].scrollIntoView({block: "nearest"});
  showOthers(row, false);
  if (row.group) setGroup(row.group, true);
  var box = new THREE.Box3();
  viewer.scene.updateMatrixWorld(true);
  row.bodies.forEach(function (b) {
    (byBody[b] || []).forEach(function (o) {
      if (o.material.color) o.material.color.setHex(colorInt(data.highlight));
      if (o.material.emissive) o.material.emissive.setHex(0x550055);
      box.expandByObject(o);
    });
  });
  marks = new THREE.Group();
  var size = Math.max(box.isEmpty() ? data.radius : box.getSize(new THREE.Vector3()).length(),
                      1e-9);
  if (row.points) {
    row.points.forEach(function (p) {
      var s = new THREE.Mesh(new THREE.SphereGeometry(size * 0.015, 16, 12),
                             new THREE.MeshBasicMaterial({color: colorInt(data.witness),
                                                          depthTest: false}));
      s.position.set(p[0], p[1], p[2]); s.renderOrder = 10; marks.add(s);
      box.expandByPoint(s.position.clone().applyMatrix4(viewer.scene.matrixWorld));
    });
    labelPoint = new THREE.Vector3().fromArray(row.points[0]);
    if (row.points.length > 1)
      labelPoint.add(new THREE.Vector3().fromArray(row.points[1])).multiplyScalar(0.5);
  }
  if (row.normal && row.points) {
    var n = new THREE.Vector3().fromArray(row.normal);
    if (n.lengthSq() > 0) {
      var arrow = new THREE.ArrowHelper(n.normalize(), new THREE.Vector3().fromArray(row.points[0]),
                                        size * 0.25, colorInt(data.normal), size * 0.06,
                                        size * 0.03);
      arrow.traverse(function (o) { if (o.material) { o.material.depthTest = false; }
                                    o.renderOrder = 11; });
      marks.add(arrow);
    }
  }
  viewer.scene.add(marks);
  if (row.label) { label.textContent = row.label; label.style.display = "block"; }
  if (!box.isEmpty()) frame(box);
  viewer.set_dirty();
}
function fromHash() {
  var m = /pair=(\d+)/.exec(location.hash);
  choose(m ? parseInt(m[1], 10) : -1);
}
window.addEventListener("hashchange", fromHash);
fromHash();

// the label follows its point
var pane = document.getElementById("meshcat-pane");
function follow() {
  if (labelPoint) {
    // meshcat turns its scene (z up); the page's coordinates are the scene's
    var p = labelPoint.clone().applyMatrix4(viewer.scene.matrixWorld).project(viewer.camera);
    var rect = viewer.renderer.domElement.getBoundingClientRect();
    label.style.left = (rect.left + (p.x + 1) / 2 * rect.width + 12) + "px";
    label.style.top = (rect.top + (1 - p.y) / 2 * rect.height - 12) + "px";
  }
  requestAnimationFrame(follow);
}
follow();
var status = document.getElementById("status");
status.textContent = data.bodies.length + " bodies, " + data.objects.length + " meshes drawn";
document.documentElement.setAttribute("data-meshcol-ready", String(data.objects.length));
})();
