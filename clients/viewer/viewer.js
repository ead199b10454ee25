// Chasles trajectory viewer: the browser side of the self-contained page written by
// `chasles view`. Reads the global CHASLES_VIEW (see README.md in this directory), draws the
// robots, the scene and the trajectory with three.js r111 (global THREE, OrbitControls), plays the
// frames back and plots the joints. Once drawn it publishes its state in window.chaslesViewer and
// in <pre id="chasles-state"> for tests.
//
// Plain browser script: no modules, no build step, no network.
(function () {
  'use strict';

  // ---------------------------------------------------------------------------------------------
  // Errors: uncaught errors, unhandled rejections and console.error calls all end up in `errors`.
  // ---------------------------------------------------------------------------------------------

  const errors = [];
  let published = false;  // once true, every new error re-publishes the state

  function describe(value) {
    if (value instanceof Error) return value.message || String(value);
    if (typeof value === 'string') return value;
    try {
      return JSON.stringify(value);
    } catch (e) {
      return String(value);
    }
  }

  function recordError(text) {
    errors.push(String(text));
    showErrorsInPanel();
    if (published) publishState();
  }

  const originalConsoleError = console.error.bind(console);

  // Reports one of our own failures (caught, so the page keeps going) without going through
  // the console.error wrapper twice.
  function reportFailure(what, error) {
    recordError(what + ': ' + describe(error));
    originalConsoleError('chasles viewer: ' + what, error);
  }

  // Runs one independent step of the set-up; a failure is listed and the next step still runs.
  function guarded(what, fn) {
    try {
      return fn();
    } catch (error) {
      reportFailure(what, error);
      return undefined;
    }
  }

  (function installErrorCapture() {
    const early = window.__chaslesEarly;
    if (early) {
      early.errors.forEach(function (text) { errors.push(text); });
      window.removeEventListener('error', early.onError);
      window.removeEventListener('unhandledrejection', early.onRejection);
    }
    window.onerror = function (message, source, line, column, error) {
      const where = source ? ' (' + source + ':' + line + ':' + column + ')' : '';
      recordError((error && error.message ? error.message : String(message)) + where);
      return false;
    };
    window.addEventListener('unhandledrejection', function (event) {
      recordError('Unhandled rejection: ' + describe(event.reason));
    });
    console.error = function () {
      const parts = [];
      for (let i = 0; i < arguments.length; i++) parts.push(describe(arguments[i]));
      recordError('console.error: ' + parts.join(' '));
      return originalConsoleError.apply(null, arguments);
    };
    window.chaslesViewer = { ready: false, errors: errors };
  })();

  // ---------------------------------------------------------------------------------------------
  // Small helpers
  // ---------------------------------------------------------------------------------------------

  const $ = function (id) { return document.getElementById(id); };

  function asArray(value) { return Array.isArray(value) ? value : []; }

  function isNumber(value) { return typeof value === 'number' && isFinite(value); }

  function numberOr(value, fallback) { return isNumber(value) ? value : fallback; }

  function clamp(value, lo, hi) { return value < lo ? lo : value > hi ? hi : value; }

  // A limit is drawn only when it is a finite, plausible number (continuous joints may come
  // with huge or missing limits).
  function isUsableLimit(value) { return isNumber(value) && Math.abs(value) < 1e6; }

  // Short labels: 3 significant digits or so (1234 -> 1.2e+3, 12.34 -> 12.3, 0.0123 -> 0.012).
  function formatValue(value) {
    const a = Math.abs(value);
    if (a >= 1000) return value.toExponential(1);
    if (a >= 100) return value.toFixed(0);
    if (a >= 10) return value.toFixed(1);
    if (a >= 0.1 || a < 1e-9) {
      const text = value.toFixed(2);
      return text === '-0.00' ? '0.00' : text;
    }
    return String(Number(value.toPrecision(2)));
  }

  // A value with as many decimals as a range of `span` needs for ~3 significant digits
  // (the plots' live read-outs: no 0.0001 of numerical noise on a +-4 axis).
  function formatAtScale(value, span) {
    const decimals = clamp(2 - Math.floor(Math.log10(span > 0 ? span : 1)), 0, 6);
    const text = value.toFixed(decimals);
    return /^-0\.?0*$/.test(text) ? text.slice(1) : text;
  }

  // 1, 2 or 5 times a power of ten, close to `rough`.
  function niceStep(rough) {
    if (!(rough > 0)) return 1;
    const power = Math.pow(10, Math.floor(Math.log10(rough)));
    const mantissa = rough / power;
    return (mantissa < 1.5 ? 1 : mantissa < 3.5 ? 2 : mantissa < 7.5 ? 5 : 10) * power;
  }

  // Binary search in an increasing array: the index i with times[i] <= t < times[i + 1],
  // and the fraction of the way from times[i] to times[i + 1]. Clamped at both ends.
  function bracket(times, t) {
    const n = times.length;
    if (n === 0) return null;
    if (n === 1 || t <= times[0]) return { i0: 0, i1: 0, alpha: 0 };
    if (t >= times[n - 1]) return { i0: n - 1, i1: n - 1, alpha: 0 };
    let lo = 0;
    let hi = n - 1;
    while (hi - lo > 1) {
      const mid = (lo + hi) >> 1;
      if (times[mid] <= t) lo = mid; else hi = mid;
    }
    const span = times[hi] - times[lo];
    return { i0: lo, i1: hi, alpha: span > 0 ? (t - times[lo]) / span : 0 };
  }

  // ---------------------------------------------------------------------------------------------
  // The view data
  // ---------------------------------------------------------------------------------------------

  let view = null;
  try {
    // `const CHASLES_VIEW` from the data script is a global lexical binding, not a window property.
    view = (typeof CHASLES_VIEW !== 'undefined') ? CHASLES_VIEW : null;  // eslint-disable-line no-undef
  } catch (error) {
    view = null;
  }
  if (!view || typeof view !== 'object') {
    recordError('CHASLES_VIEW is missing or not an object');
    view = {};
  }
  // Without three.js nothing can be drawn: publish the failure and stop.
  if (typeof THREE === 'undefined') {
    recordError('three.js (THREE) is missing: nothing can be drawn');
    const failed = { ready: true, errors: errors, load_ms: Math.round(performance.now() * 10) / 10, frames: 0, robots: [] };
    window.chaslesViewer = failed;
    const element = document.getElementById('chasles-state');
    if (element) element.textContent = JSON.stringify(failed);
    return;
  }

  const viewRobots = asArray(view.robots);
  const viewScene = (view.scene && typeof view.scene === 'object') ? view.scene : {};

  // The playback runs over [0, duration]; without a usable duration, the longest frame times.
  const duration = (function () {
    if (isNumber(view.duration) && view.duration >= 0) return view.duration;
    let longest = 0;
    viewRobots.forEach(function (robot) {
      const times = asArray(robot && robot.frames && robot.frames.t);
      if (times.length && isNumber(times[times.length - 1])) longest = Math.max(longest, times[times.length - 1]);
    });
    return longest;
  })();

  // ---------------------------------------------------------------------------------------------
  // Colours, materials and shared geometry
  // ---------------------------------------------------------------------------------------------

  const COLORS = {
    background: 0x2a2c30,
    robot: 0xcfd3d9,
    object: 0x5b7ea6,
    voxel: 0xff8a2a,
    sphere: 0x4cd964,
    trail: 0xffd23f,
    waypoint: 0xfff1a8,
    gridMajor: 0x5c6068,
    gridMinor: 0x3f4248,
    markers: { min_clearance: 0x2ed3ff, failure: 0xff3b4e, other: 0xd36bff },
  };

  const materials = {
    robot: new THREE.MeshPhongMaterial({ color: COLORS.robot, specular: 0x222222, shininess: 40 }),
    // Translucent, so a robot inside a shelf, a cage or a corridor stays in sight.
    object: new THREE.MeshPhongMaterial({ color: COLORS.object, specular: 0x111111, shininess: 20, transparent: true,
                                          opacity: 0.55, depthWrite: false }),
    // triangle meshes may come with mixed windings: draw both sides
    robotMesh: new THREE.MeshPhongMaterial({ color: COLORS.robot, specular: 0x222222, shininess: 40, side: THREE.DoubleSide }),
    objectMesh: new THREE.MeshPhongMaterial({ color: COLORS.object, specular: 0x111111, shininess: 20, side: THREE.DoubleSide,
                                              transparent: true, opacity: 0.55, depthWrite: false }),
    voxel: new THREE.MeshLambertMaterial({ color: COLORS.voxel, transparent: true, opacity: 0.5, depthWrite: false }),
    sphere: new THREE.MeshLambertMaterial({ color: COLORS.sphere, transparent: true, opacity: 0.35, depthWrite: false }),
    trail: new THREE.LineBasicMaterial({ color: COLORS.trail }),
    // the trail's moving dot stays visible inside the link's shapes
    dot: new THREE.MeshBasicMaterial({ color: COLORS.trail, depthTest: false, transparent: true }),
    waypoint: new THREE.MeshLambertMaterial({ color: COLORS.waypoint, emissive: 0x403a10 }),
  };

  // Unit shapes, scaled per use (three.js transforms normals with the normal matrix, so
  // non-uniform scales keep the shading right). three.js cylinders run along y: turn them to z.
  const geometries = {
    sphere: new THREE.SphereBufferGeometry(1, 24, 16),
    smallSphere: new THREE.SphereBufferGeometry(1, 12, 8),
    box: new THREE.BoxBufferGeometry(1, 1, 1),
    cylinder: new THREE.CylinderBufferGeometry(1, 1, 1, 32, 1, false).rotateX(Math.PI / 2),
    openCylinder: new THREE.CylinderBufferGeometry(1, 1, 1, 32, 1, true).rotateX(Math.PI / 2),
  };

  // A zero scale makes the normal matrix singular (NaN shading): keep sizes above a micrometre.
  function size(value) { return Math.max(Math.abs(numberOr(value, 0)), 1e-6); }

  // pose = [x, y, z, qw, qx, qy, qz]; three.js quaternions are (x, y, z, w).
  function applyPose(object, pose) {
    if (!Array.isArray(pose) || pose.length < 7) return;
    object.position.set(numberOr(pose[0], 0), numberOr(pose[1], 0), numberOr(pose[2], 0));
    object.quaternion.set(numberOr(pose[4], 0), numberOr(pose[5], 0), numberOr(pose[6], 0), numberOr(pose[3], 1));
    object.quaternion.normalize();
  }

  // A triangle mesh with one normal per face (CAD meshes look wrong with averaged normals).
  function buildMeshGeometry(vertices, triangles) {
    const vertexCount = Math.floor(vertices.length / 3);
    const positions = new Float32Array(triangles.length * 3);
    let used = 0;
    for (let i = 0; i + 2 < triangles.length; i += 3) {
      const a = triangles[i], b = triangles[i + 1], c = triangles[i + 2];
      if (!(a < vertexCount && b < vertexCount && c < vertexCount && a >= 0 && b >= 0 && c >= 0)) continue;
      for (const index of [a, b, c]) {
        positions[used++] = vertices[3 * index];
        positions[used++] = vertices[3 * index + 1];
        positions[used++] = vertices[3 * index + 2];
      }
    }
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(positions.subarray(0, used), 3));
    geometry.computeVertexNormals();  // non-indexed: the face normal at each corner
    geometry.computeBoundingSphere();
    return geometry;
  }

  const warnedShapeTypes = {};
  const notes = [];  // remarks on the data shown in the panel (not errors)

  // A three.js object for one shape of the view data (link or scene object), posed in its parent
  // frame, or null for an unknown or empty shape. `hoverText` becomes the tooltip; triangle meshes
  // use `meshMaterial`.
  function makeShape(shape, material, meshMaterial, hoverText) {
    if (!shape || typeof shape !== 'object') return null;
    let object = null;
    switch (shape.type) {
      case 'sphere': {
        object = new THREE.Mesh(geometries.sphere, material);
        object.scale.setScalar(size(shape.radius));
        break;
      }
      case 'box': {
        const extents = asArray(shape.size);
        object = new THREE.Mesh(geometries.box, material);
        object.scale.set(size(extents[0]), size(extents[1]), size(extents[2]));
        break;
      }
      case 'cylinder': {
        object = new THREE.Mesh(geometries.cylinder, material);
        object.scale.set(size(shape.radius), size(shape.radius), size(shape.length));
        break;
      }
      case 'capsule': {
        // r111 has no capsule geometry: an open cylinder and two spheres at its ends.
        const radius = size(shape.radius);
        const length = Math.abs(numberOr(shape.length, 0));
        object = new THREE.Group();
        const body = new THREE.Mesh(geometries.openCylinder, material);
        body.scale.set(radius, radius, size(length));
        object.add(body);
        for (const end of [-0.5, 0.5]) {
          const cap = new THREE.Mesh(geometries.sphere, material);
          cap.scale.setScalar(radius);
          cap.position.z = end * length;
          object.add(cap);
        }
        break;
      }
      case 'mesh': {
        const vertices = asArray(shape.vertices);
        const triangles = asArray(shape.triangles);
        if (vertices.length < 9 || triangles.length < 3) return null;
        object = new THREE.Mesh(buildMeshGeometry(vertices, triangles), meshMaterial);
        break;
      }
      default:
        if (!warnedShapeTypes[shape.type]) {
          warnedShapeTypes[shape.type] = true;
          notes.push('shape type "' + shape.type + '" is not drawn');
        }
        return null;
    }
    applyPose(object, shape.pose);
    object.traverse(function (child) { if (child.isMesh) child.userData.hoverText = hoverText; });
    return object;
  }

  // ---------------------------------------------------------------------------------------------
  // Scene graph
  // ---------------------------------------------------------------------------------------------

  const scene = new THREE.Scene();
  scene.background = new THREE.Color(COLORS.background);

  const camera = new THREE.PerspectiveCamera(45, 1, 0.01, 100);
  camera.up.set(0, 0, 1);  // z up; must be set before OrbitControls is created
  camera.position.set(2, -2.5, 1.8);

  const groups = {
    objects: new THREE.Group(),
    voxels: new THREE.Group(),
    robots: new THREE.Group(),
    trails: new THREE.Group(),
    markers: new THREE.Group(),
    helpers: new THREE.Group(),
  };
  for (const name in groups) {
    groups[name].name = name;
    scene.add(groups[name]);
  }

  const hoverTargets = [];  // meshes with userData.hoverText, for the canvas tooltip
  const sceneBounds = new THREE.Box3();  // what the camera frames

  function addLights() {
    const sky = new THREE.HemisphereLight(0xffffff, 0x3a3d44, 0.55);
    sky.position.set(0, 0, 1);  // hemisphere "up" along z
    scene.add(sky);
    const key = new THREE.DirectionalLight(0xffffff, 0.7);
    key.position.set(2, -3, 5);
    scene.add(key);
    const fill = new THREE.DirectionalLight(0xffffff, 0.25);
    fill.position.set(-3, 2, 1);
    scene.add(fill);
  }

  function buildObjects() {
    asArray(viewScene.objects).forEach(function (entry, index) {
      guarded('scene object ' + index, function () {
        const name = (entry && entry.name) || 'object ' + index;
        const object = makeShape(entry && entry.shape, materials.object, materials.objectMesh, 'object: ' + name);
        if (!object) return;
        object.name = name;
        groups.objects.add(object);
        object.traverse(function (child) { if (child.isMesh) hoverTargets.push(child); });
      });
    });
    if (groups.objects.children.length) {
      groups.objects.updateMatrixWorld(true);
      sceneBounds.expandByObject(groups.objects);
    }
  }

  // OctoMap leaves as one InstancedMesh per map: one draw call, ~100k cubes are no problem.
  function buildVoxels() {
    asArray(viewScene.voxels).forEach(function (map, index) {
      guarded('voxels ' + index, function () {
        const centres = asArray(map && map.centres);
        const count = Math.floor(centres.length / 3);
        if (count === 0) return;
        const edge = size(map.size) * 0.96;  // slight gaps show the individual cubes
        const mesh = new THREE.InstancedMesh(geometries.box, materials.voxel, count);
        const matrices = mesh.instanceMatrix.array;  // column-major 4x4 per instance
        let minX = Infinity, minY = Infinity, minZ = Infinity, maxX = -Infinity, maxY = -Infinity, maxZ = -Infinity;
        for (let i = 0; i < count; i++) {
          const x = centres[3 * i], y = centres[3 * i + 1], z = centres[3 * i + 2];
          const m = 16 * i;
          matrices[m] = edge; matrices[m + 5] = edge; matrices[m + 10] = edge; matrices[m + 15] = 1;
          matrices[m + 12] = x; matrices[m + 13] = y; matrices[m + 14] = z;
          if (x < minX) minX = x; if (x > maxX) maxX = x;
          if (y < minY) minY = y; if (y > maxY) maxY = y;
          if (z < minZ) minZ = z; if (z > maxZ) maxZ = z;
        }
        mesh.instanceMatrix.needsUpdate = true;
        // r111 culls an InstancedMesh by the bounding sphere of one cube at the origin.
        mesh.frustumCulled = false;
        mesh.name = (map && map.name) || 'voxels ' + index;
        groups.voxels.add(mesh);
        if (isFinite(minX + minY + minZ + maxX + maxY + maxZ)) {
          const half = edge / 2;
          sceneBounds.expandByPoint(new THREE.Vector3(minX - half, minY - half, minZ - half));
          sceneBounds.expandByPoint(new THREE.Vector3(maxX + half, maxY + half, maxZ + half));
        }
      });
    });
  }

  // ---------------------------------------------------------------------------------------------
  // Robots
  // ---------------------------------------------------------------------------------------------

  // One entry per robot of the view data:
  //   links[l] = { group, shapes, spheres }  (group posed per frame; shapes/spheres inside it)
  //   times (Float64Array), poses (Float64Array, frame-major, 7 numbers per link)
  const robots = [];

  function buildRobot(data, robotIndex) {
    const name = (data && data.name) || 'robot ' + (robotIndex + 1);
    const robot = {
      name: name,
      root: new THREE.Group(),
      links: [],
      times: new Float64Array(0),
      poses: new Float64Array(0),
      trailIndex: -1,
      trailPath: new THREE.Group(),
      dot: null,
      hasShapes: false,
      showShapes: true,
      showSpheres: false,
      plot: (data && data.plot && typeof data.plot === 'object') ? data.plot : null,
      plotCache: null,
      notes: [],
    };
    robot.root.name = name;
    robots.push(robot);
    groups.robots.add(robot.root);
    groups.trails.add(robot.trailPath);

    const links = asArray(data && data.links);
    links.forEach(function (link, linkIndex) {
      const linkName = (link && link.name) || 'link ' + linkIndex;
      const group = new THREE.Group();
      group.name = linkName;
      const shapes = new THREE.Group();
      shapes.name = linkName + ' shapes';
      const spheres = new THREE.Group();
      spheres.name = linkName + ' spheres';
      group.add(shapes);
      group.add(spheres);
      robot.root.add(group);
      robot.links.push({ name: linkName, group: group, shapes: shapes, spheres: spheres });

      asArray(link && link.shapes).forEach(function (shape) {
        const object = makeShape(shape, materials.robot, materials.robotMesh, name + ' / ' + linkName);
        if (!object) return;
        shapes.add(object);
        robot.hasShapes = true;
        object.traverse(function (child) { if (child.isMesh) hoverTargets.push(child); });
      });
      asArray(link && link.spheres).forEach(function (sphere, sphereIndex) {
        if (!Array.isArray(sphere) || sphere.length < 4) return;
        const mesh = new THREE.Mesh(geometries.smallSphere, materials.sphere);
        mesh.position.set(numberOr(sphere[0], 0), numberOr(sphere[1], 0), numberOr(sphere[2], 0));
        mesh.scale.setScalar(size(sphere[3]));
        mesh.userData.hoverText = name + ' / ' + linkName + ' sphere ' + sphereIndex + ' (r ' + formatValue(sphere[3]) + ' m)';
        spheres.add(mesh);
        hoverTargets.push(mesh);
      });
    });
    robot.showSpheres = !robot.hasShapes;

    readFrames(robot, data && data.frames);

    const trailLink = data && data.trail_link;
    if (Number.isInteger(trailLink) && trailLink >= 0 && trailLink < robot.links.length) {
      robot.trailIndex = trailLink;
    } else if (robot.links.length) {
      robot.notes.push('no trail link');
    }
    buildTrail(robot, asArray(data && data.waypoints));
    applyVisibility(robot);
    if (robot.times.length === 0) {
      robot.root.visible = false;  // no frame says where the links are
      robot.notes.push('no frames: the robot is not drawn');
    }
    return robot;
  }

  // Copies the frames into typed arrays (quaternions normalised) and checks their layout.
  function readFrames(robot, frames) {
    const linkCount = robot.links.length;
    const times = asArray(frames && frames.t);
    const poses = asArray(frames && frames.poses);
    const count = Math.min(times.length, poses.length);
    if (times.length !== poses.length) {
      recordError(robot.name + ': frames.t has ' + times.length + ' entries but frames.poses ' + poses.length);
    }
    const stride = 7 * linkCount;
    robot.times = new Float64Array(count);
    robot.poses = new Float64Array(count * stride);
    let badFrames = 0;
    for (let f = 0; f < count; f++) {
      robot.times[f] = numberOr(times[f], f > 0 ? robot.times[f - 1] : 0);
      const pose = poses[f];
      if (!Array.isArray(pose) || pose.length < stride) badFrames++;
      for (let l = 0; l < linkCount; l++) {
        const src = 7 * l;
        const dst = f * stride + src;
        const p = Array.isArray(pose) ? pose : [];
        robot.poses[dst] = numberOr(p[src], 0);
        robot.poses[dst + 1] = numberOr(p[src + 1], 0);
        robot.poses[dst + 2] = numberOr(p[src + 2], 0);
        let w = numberOr(p[src + 3], 1), x = numberOr(p[src + 4], 0), y = numberOr(p[src + 5], 0), z = numberOr(p[src + 6], 0);
        const norm = Math.sqrt(w * w + x * x + y * y + z * z);
        if (norm > 1e-12) { w /= norm; x /= norm; y /= norm; z /= norm; } else { w = 1; x = y = z = 0; }
        robot.poses[dst + 3] = w;
        robot.poses[dst + 4] = x;
        robot.poses[dst + 5] = y;
        robot.poses[dst + 6] = z;
      }
    }
    if (badFrames) {
      recordError(robot.name + ': ' + badFrames + ' frame(s) with fewer than ' + stride + ' pose numbers (' + linkCount + ' links)');
    }
    for (let f = 1; f < count; f++) {
      if (robot.times[f] < robot.times[f - 1]) {
        recordError(robot.name + ': frame times decrease at frame ' + f);
        break;
      }
    }
  }

  // Scale of the small markers (trail dot, waypoints, markers) relative to the whole scene.
  let dotRadius = 0.012;

  function buildTrail(robot, waypoints) {
    if (robot.trailIndex < 0) return;
    const count = robot.times.length;
    const stride = 7 * robot.links.length;
    if (count >= 2) {
      const positions = new Float32Array(3 * count);
      for (let f = 0; f < count; f++) {
        const src = f * stride + 7 * robot.trailIndex;
        positions[3 * f] = robot.poses[src];
        positions[3 * f + 1] = robot.poses[src + 1];
        positions[3 * f + 2] = robot.poses[src + 2];
      }
      const geometry = new THREE.BufferGeometry();
      geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
      const line = new THREE.Line(geometry, materials.trail);
      line.name = robot.name + ' trail';
      robot.trailPath.add(line);
    }
    if (count >= 1) {
      robot.dot = new THREE.Mesh(geometries.smallSphere, materials.dot);
      robot.dot.name = robot.name + ' trail dot';
      robot.dot.renderOrder = 10;  // after everything else (it ignores depth)
      robot.trailPath.add(robot.dot);
    }
    waypoints.forEach(function (point, index) {
      if (!Array.isArray(point) || point.length < 3) return;
      const mesh = new THREE.Mesh(geometries.smallSphere, materials.waypoint);
      mesh.position.set(numberOr(point[0], 0), numberOr(point[1], 0), numberOr(point[2], 0));
      mesh.userData.isWaypoint = true;
      mesh.userData.hoverText = robot.name + ' waypoint ' + index;
      robot.trailPath.add(mesh);
      hoverTargets.push(mesh);
    });
  }

  function applyVisibility(robot) {
    robot.links.forEach(function (link) {
      link.shapes.visible = robot.showShapes;
      link.spheres.visible = robot.showSpheres;
    });
  }

  const tmpQuatA = new THREE.Quaternion();
  const tmpQuatB = new THREE.Quaternion();

  // Poses every link group at time t: positions lerped and orientations slerped between the two
  // nearest frames (clamped to the first/last frame outside their span).
  function updateRobotAt(robot, t) {
    const where = bracket(robot.times, t);
    if (!where) return;
    const stride = 7 * robot.links.length;
    const P = robot.poses;
    const a = where.alpha;
    for (let l = 0; l < robot.links.length; l++) {
      const b0 = where.i0 * stride + 7 * l;
      const b1 = where.i1 * stride + 7 * l;
      const group = robot.links[l].group;
      group.position.set(
        P[b0] + (P[b1] - P[b0]) * a,
        P[b0 + 1] + (P[b1 + 1] - P[b0 + 1]) * a,
        P[b0 + 2] + (P[b1 + 2] - P[b0 + 2]) * a);
      tmpQuatA.set(P[b0 + 4], P[b0 + 5], P[b0 + 6], P[b0 + 3]);
      if (a > 0) {
        tmpQuatB.set(P[b1 + 4], P[b1 + 5], P[b1 + 6], P[b1 + 3]);
        tmpQuatA.slerp(tmpQuatB, a).normalize();
      }
      group.quaternion.copy(tmpQuatA);
    }
    if (robot.dot && robot.trailIndex >= 0) robot.dot.position.copy(robot.links[robot.trailIndex].group.position);
  }

  // Robot extent over the whole motion: the drawn shapes at a few times plus every link origin of
  // every frame.
  function expandBoundsByRobot(robot) {
    if (robot.times.length === 0) return;
    const stride = 7 * robot.links.length;
    const point = new THREE.Vector3();
    for (let i = 0; i < robot.poses.length; i += 7) {
      point.set(robot.poses[i], robot.poses[i + 1], robot.poses[i + 2]);
      sceneBounds.expandByPoint(point);
    }
    if (stride === 0) return;
    for (const t of [0, duration / 2, duration]) {
      updateRobotAt(robot, t);
      robot.root.updateMatrixWorld(true);
      robot.links.forEach(function (link) {
        sceneBounds.expandByObject(link.shapes);
        sceneBounds.expandByObject(link.spheres);
      });
    }
    robot.trailPath.children.forEach(function (child) {
      if (child.userData.isWaypoint) sceneBounds.expandByPoint(child.position);
    });
  }

  // ---------------------------------------------------------------------------------------------
  // Markers
  // ---------------------------------------------------------------------------------------------

  const markerMeshes = [];

  function buildMarkers() {
    const list = $('markers');
    asArray(view.markers).forEach(function (marker, index) {
      guarded('marker ' + index, function () {
        const position = asArray(marker && marker.position);
        if (position.length < 3) return;
        const kind = (marker && marker.kind) || 'marker';
        const text = (marker && marker.text) || kind;
        const color = COLORS.markers[kind] !== undefined ? COLORS.markers[kind] : COLORS.markers.other;
        const material = new THREE.MeshPhongMaterial({ color: color, emissive: new THREE.Color(color).multiplyScalar(0.35) });
        const mesh = new THREE.Mesh(geometries.sphere, material);
        mesh.position.set(numberOr(position[0], 0), numberOr(position[1], 0), numberOr(position[2], 0));
        mesh.userData.hoverText = text;
        mesh.name = 'marker ' + index;
        groups.markers.add(mesh);
        markerMeshes.push(mesh);
        hoverTargets.push(mesh);
        sceneBounds.expandByPoint(mesh.position);

        if (list) {
          const item = document.createElement('li');
          item.title = text + '\n(' + kind.replace(/_/g, ' ') + '; click to centre the view on it)';
          const swatch = document.createElement('span');
          swatch.className = 'swatch';
          swatch.style.background = '#' + new THREE.Color(color).getHexString();
          const label = document.createElement('span');
          label.textContent = text;
          item.appendChild(swatch);
          item.appendChild(label);
          item.addEventListener('click', function () {
            if (!controls) return;
            controls.target.copy(mesh.position);
            controls.update();
            requestRender();
          });
          list.appendChild(item);
        }
      });
    });
    if (markerMeshes.length && $('markers-section')) $('markers-section').hidden = false;
  }

  // ---------------------------------------------------------------------------------------------
  // Camera framing, ground grid, sizes of the small spheres
  // ---------------------------------------------------------------------------------------------

  // The framed view: the camera looks at `target` from `direction`, far enough to see a sphere of
  // `radius` whatever the canvas's aspect.
  const home = { target: new THREE.Vector3(), direction: new THREE.Vector3(1.0, -1.35, 0.8).normalize(), radius: 1 };

  function frameScene() {
    if (sceneBounds.isEmpty()) {
      sceneBounds.set(new THREE.Vector3(-0.5, -0.5, 0), new THREE.Vector3(0.5, 0.5, 1));
    }
    const centre = sceneBounds.getCenter(new THREE.Vector3());
    const extent = sceneBounds.getSize(new THREE.Vector3());
    const radius = Math.max(0.5 * extent.length(), 0.25);

    dotRadius = clamp(radius * 0.012, 0.004, 0.05);
    robots.forEach(function (robot) {
      robot.trailPath.children.forEach(function (child) {
        if (child === robot.dot) child.scale.setScalar(dotRadius * 1.2);
        else if (child.userData.isWaypoint) child.scale.setScalar(dotRadius);
      });
    });
    markerMeshes.forEach(function (mesh) { mesh.scale.setScalar(dotRadius * 1.6); });

    home.target.copy(centre);
    home.radius = radius;
    resetView();

    // Ground grid in the xy plane (GridHelper lies in xz), under everything, with ~10-40 cells.
    const span = Math.max(extent.x, extent.y, 0.5) * 1.6;
    const step = niceStep(span / 20);
    const cells = Math.max(2, 2 * Math.ceil(span / step / 2));
    const grid = new THREE.GridHelper(cells * step, cells, COLORS.gridMajor, COLORS.gridMinor);
    grid.rotation.x = Math.PI / 2;
    grid.position.set(Math.round(centre.x / step) * step, Math.round(centre.y / step) * step, Math.min(0, sceneBounds.min.z));
    grid.name = 'grid';
    groups.helpers.add(grid);
    const axes = new THREE.AxesHelper(step * 2);  // the world frame: x red, y green, z blue
    groups.helpers.add(axes);
  }

  function resetView() {
    const halfHeight = camera.fov * Math.PI / 360;  // half the vertical field of view [rad]
    const halfWidth = Math.atan(Math.tan(halfHeight) * camera.aspect);
    const distance = home.radius / Math.sin(Math.min(halfHeight, halfWidth)) * 1.02;
    camera.near = Math.max(distance / 1000, 0.001);
    camera.far = distance + home.radius * 50;
    camera.updateProjectionMatrix();
    camera.position.copy(home.target).addScaledVector(home.direction, distance);
    if (controls) {
      controls.target.copy(home.target);
      controls.update();
    } else {
      camera.lookAt(home.target);
    }
    requestRender();
  }

  // ---------------------------------------------------------------------------------------------
  // Renderer, controls, render loop
  // ---------------------------------------------------------------------------------------------

  let renderer = null;
  let controls = null;
  let renderRequested = true;
  const viewElement = $('view');

  function requestRender() { renderRequested = true; }

  function createRenderer() {
    try {
      renderer = new THREE.WebGLRenderer({ antialias: true });
    } catch (error) {
      renderer = null;
      reportFailure('WebGL is not available', error);
      const message = $('view-message');
      if (message) {
        message.textContent = 'WebGL is not available in this browser: the 3-D view cannot be drawn.';
        message.hidden = false;
      }
      return;
    }
    renderer.setPixelRatio(window.devicePixelRatio || 1);
    viewElement.appendChild(renderer.domElement);
    if (typeof THREE.OrbitControls === 'function') {
      controls = new THREE.OrbitControls(camera, renderer.domElement);
      controls.screenSpacePanning = true;
      controls.addEventListener('change', requestRender);
    } else {
      recordError('THREE.OrbitControls is missing: the view cannot be rotated');
    }
    resizeRenderer();
  }

  function resizeRenderer() {
    if (!renderer) return;
    const width = Math.max(viewElement.clientWidth, 1);
    const height = Math.max(viewElement.clientHeight, 1);
    renderer.setSize(width, height, false);  // CSS sizes the canvas to its container
    camera.aspect = width / height;
    camera.updateProjectionMatrix();
    requestRender();
  }

  function render() {
    if (!renderer) return;
    renderer.render(scene, camera);
    renderRequested = false;
  }

  // Playback state
  let currentTime = 0;
  let playing = false;
  let speed = 1;
  let lastTick = null;

  function setTime(t, fromSlider) {
    currentTime = clamp(isNumber(t) ? t : 0, 0, duration);
    robots.forEach(function (robot) { updateRobotAt(robot, currentTime); });
    if (!fromSlider && ui.slider) ui.slider.value = String(currentTime);
    if (ui.timeLabel) ui.timeLabel.textContent = currentTime.toFixed(2) + ' / ' + duration.toFixed(2) + ' s';
    drawPlotCursors();
    requestRender();
  }

  function setPlaying(on) {
    playing = on && duration > 0;
    lastTick = null;
    if (ui.play) {
      ui.play.innerHTML = playing ? '&#10074;&#10074;' : '&#9654;';
      ui.play.setAttribute('aria-label', playing ? 'Pause' : 'Play');
    }
  }

  function togglePlay() {
    if (!playing && currentTime >= duration) setTime(0);
    setPlaying(!playing);
  }

  function tick(now) {
    requestAnimationFrame(tick);
    if (playing) {
      const dt = lastTick === null ? 0 : Math.min((now - lastTick) / 1000, 0.1);
      lastTick = now;
      let t = currentTime + dt * speed;
      if (t >= duration) {
        if (ui.loop && ui.loop.checked && duration > 0) {
          t = t % duration;
        } else {
          t = duration;
          setPlaying(false);
        }
      }
      setTime(t);
    }
    if (pointer.moved) updateHover();
    if (renderRequested) render();
  }

  // Tooltip on the canvas: what is under the mouse (marker, waypoint, link, object).
  const pointer = { x: 0, y: 0, moved: false, inside: false };
  const raycaster = new THREE.Raycaster();

  function isShown(object) {
    for (let o = object; o; o = o.parent) if (!o.visible) return false;
    return true;
  }

  function updateHover() {
    pointer.moved = false;
    if (!renderer || !pointer.inside) return;
    const rect = renderer.domElement.getBoundingClientRect();
    const ndc = new THREE.Vector2(((pointer.x - rect.left) / rect.width) * 2 - 1, -((pointer.y - rect.top) / rect.height) * 2 + 1);
    raycaster.setFromCamera(ndc, camera);
    const hits = raycaster.intersectObjects(hoverTargets, false);
    let text = '';
    for (const hit of hits) {
      if (isShown(hit.object)) { text = hit.object.userData.hoverText || ''; break; }
    }
    if (renderer.domElement.title !== text) renderer.domElement.title = text;
  }

  // ---------------------------------------------------------------------------------------------
  // Side panel
  // ---------------------------------------------------------------------------------------------

  const ui = {
    play: $('play'),
    slider: $('time-slider'),
    timeLabel: $('time-label'),
    speed: $('speed'),
    loop: $('loop'),
    robotSelect: $('robot-select'),
    showShapes: $('show-shapes'),
    showSpheres: $('show-spheres'),
    plots: $('plots'),
  };
  let selectedRobot = 0;

  function showErrorsInPanel() {
    const box = document.getElementById('errors');
    if (!box) return;
    box.hidden = errors.length === 0;
    box.textContent = '';
    errors.forEach(function (text) {
      const line = document.createElement('div');
      line.textContent = text;
      box.appendChild(line);
    });
  }

  // Remarks on the data (not errors), after the info lines.
  function showNotes() {
    const info = $('info');
    if (!info) return;
    notes.forEach(function (text) {
      const item = document.createElement('li');
      item.className = 'muted';
      item.textContent = text;
      info.appendChild(item);
    });
  }

  function fillHeader() {
    const title = typeof view.title === 'string' && view.title ? view.title : 'Chasles trajectory';
    document.title = title;
    if ($('title')) $('title').textContent = title;
    const info = $('info');
    if (info) {
      asArray(view.info).forEach(function (line) {
        const item = document.createElement('li');
        item.textContent = String(line);
        info.appendChild(item);
      });
    }
  }

  function bindToolbar() {
    if (ui.slider) {
      ui.slider.max = String(duration > 0 ? duration : 1);
      ui.slider.disabled = !(duration > 0);
      ui.slider.addEventListener('input', function () { setTime(parseFloat(ui.slider.value), true); });
    }
    if (ui.play) {
      ui.play.disabled = !(duration > 0);
      ui.play.addEventListener('click', togglePlay);
    }
    if (ui.speed) {
      speed = parseFloat(ui.speed.value) || 1;
      ui.speed.addEventListener('change', function () { speed = parseFloat(ui.speed.value) || 1; });
    }
    if ($('reset-view')) $('reset-view').addEventListener('click', resetView);
    window.addEventListener('keydown', function (event) {
      const tag = (event.target && event.target.tagName) || '';
      if (event.key === ' ' && !/^(INPUT|SELECT|TEXTAREA|BUTTON)$/.test(tag)) {
        event.preventDefault();
        togglePlay();
      }
    });
    if (renderer) {
      const canvas = renderer.domElement;
      canvas.addEventListener('pointermove', function (event) {
        pointer.x = event.clientX;
        pointer.y = event.clientY;
        pointer.inside = event.buttons === 0;  // no tooltips while orbiting
        pointer.moved = true;
      });
      canvas.addEventListener('pointerleave', function () { pointer.inside = false; canvas.title = ''; });
    }
  }

  function bindDisplayToggles() {
    const toggle = function (id, object) {
      const box = $(id);
      if (!box) return;
      object.visible = box.checked;
      box.addEventListener('change', function () { object.visible = box.checked; requestRender(); });
    };
    toggle('show-trail', groups.trails);
    toggle('show-objects', groups.objects);
    toggle('show-voxels', groups.voxels);
    toggle('show-markers', groups.markers);
    toggle('show-grid', groups.helpers);
    if (!asArray(viewScene.voxels).length && $('show-voxels')) $('show-voxels').parentNode.hidden = true;
    if (!markerMeshes.length && $('show-markers')) $('show-markers').parentNode.hidden = true;
    if (!groups.objects.children.length && $('show-objects')) $('show-objects').parentNode.hidden = true;
    if (!groups.trails.children.some(function (path) { return path.children.length > 0; }) && $('show-trail')) {
      $('show-trail').parentNode.hidden = true;
    }

    if (ui.showShapes) {
      ui.showShapes.addEventListener('change', function () {
        const robot = robots[selectedRobot];
        if (!robot) return;
        robot.showShapes = ui.showShapes.checked;
        applyVisibility(robot);
        requestRender();
      });
    }
    if (ui.showSpheres) {
      ui.showSpheres.addEventListener('change', function () {
        const robot = robots[selectedRobot];
        if (!robot) return;
        robot.showSpheres = ui.showSpheres.checked;
        applyVisibility(robot);
        requestRender();
      });
    }
  }

  function buildRobotSelector() {
    const select = ui.robotSelect;
    if (select && robots.length > 1) {
      robots.forEach(function (robot, index) {
        const option = document.createElement('option');
        option.value = String(index);
        option.textContent = robot.name;
        select.appendChild(option);
      });
      select.hidden = false;
      select.addEventListener('change', function () { selectRobot(parseInt(select.value, 10) || 0); });
    }
    if (!robots.length) {
      if ($('robot-section')) $('robot-section').hidden = true;
      if ($('plots-section')) $('plots-section').hidden = true;
    }
    selectRobot(0);
  }

  // The panel's robot part (toggles, notes, plots) follows the selected robot.
  function selectRobot(index) {
    selectedRobot = index;
    const robot = robots[index];
    if (!robot) {
      if (ui.plots) ui.plots.innerHTML = '<p class="muted">No robot.</p>';
      return;
    }
    if ($('robot-name')) $('robot-name').textContent = robots.length > 1 ? '' : robot.name;
    if (ui.showShapes) {
      ui.showShapes.checked = robot.showShapes;
      ui.showShapes.disabled = !robot.hasShapes;
      ui.showShapes.parentNode.title = robot.hasShapes ? '' : 'this robot has no collision shapes';
    }
    if (ui.showSpheres) {
      ui.showSpheres.checked = robot.showSpheres;
      const anySpheres = robot.links.some(function (link) { return link.spheres.children.length > 0; });
      ui.showSpheres.disabled = !anySpheres;
      ui.showSpheres.parentNode.title = anySpheres ? '' : 'this robot has no collision spheres';
    }
    if ($('robot-notes')) $('robot-notes').textContent = robot.notes.join('; ');
    guarded('plots', function () { buildPlots(robot); });
  }

  // Keeps receiving a drag's pointer events when the pointer leaves the element.
  function capturePointer(element, event) {
    try {
      element.setPointerCapture(event.pointerId);
    } catch (error) {
      // synthetic events have no active pointer: the drag still works inside the element
    }
  }

  // Drag the splitter to resize the panel; the 3-D view takes the rest.
  function bindSplitter() {
    const splitter = $('splitter');
    const panel = $('panel');
    if (!splitter || !panel) return;
    splitter.addEventListener('pointerdown', function (event) {
      event.preventDefault();
      capturePointer(splitter, event);
      splitter.classList.add('dragging');
      document.body.classList.add('resizing');
      const move = function (e) {
        const width = clamp(window.innerWidth - e.clientX, 220, Math.max(240, window.innerWidth * 0.7));
        document.documentElement.style.setProperty('--panel-width', width + 'px');
        onLayoutChange();
      };
      const up = function () {
        splitter.removeEventListener('pointermove', move);
        splitter.removeEventListener('pointerup', up);
        splitter.classList.remove('dragging');
        document.body.classList.remove('resizing');
      };
      splitter.addEventListener('pointermove', move);
      splitter.addEventListener('pointerup', up);
    });
  }

  let layoutPending = false;
  let lastPlotWidth = -1;

  // Window or panel resized: resize the renderer, and redraw the plots if their width changed
  // (at most once per animation frame).
  function onLayoutChange() {
    if (layoutPending) return;
    layoutPending = true;
    requestAnimationFrame(function () {
      layoutPending = false;
      resizeRenderer();
      if (ui.plots && ui.plots.clientWidth !== lastPlotWidth) drawAllPlots();
    });
  }

  // ---------------------------------------------------------------------------------------------
  // Joint plots: per joint one canvas with three rows (q, qd, qdd) drawn once per resize, and an
  // overlay canvas for the time cursor, redrawn when the time changes.
  // ---------------------------------------------------------------------------------------------

  const PLOT = {
    rowHeight: 46,
    rowGap: 5,
    top: 3,
    axisHeight: 14,
    left: 44,
    right: 6,
    quantities: [
      { key: 'q', label: 'q', color: '#7fb8ff' },
      { key: 'qd', label: 'qd', color: '#8ee68e' },
      { key: 'qdd', label: 'qdd', color: '#ffb86b' },
    ],
    limitColor: '#ff7b7b',
  };
  PLOT.height = PLOT.top + 3 * PLOT.rowHeight + 2 * PLOT.rowGap + PLOT.axisHeight;

  let plotEntries = [];  // { joint, canvas, overlay, width } for the selected robot
  let plotData = null;   // the selected robot's plot cache

  // Plot samples as typed arrays per quantity and joint, with the value range of each row
  // (data and limits). Computed once per robot.
  function preparePlotData(robot) {
    if (robot.plotCache) return robot.plotCache;
    const plot = robot.plot;
    const times = asArray(plot && plot.t);
    let jointCount = asArray(plot && plot.joint_names).length;
    if (!jointCount) {
      const first = asArray(plot && plot.q)[0];
      jointCount = Array.isArray(first) ? first.length : 0;
    }
    const cache = { t: null, tEnd: 1, joints: [], empty: true };
    robot.plotCache = cache;
    if (!times.length || !jointCount) return cache;

    let sampleCount = times.length;
    PLOT.quantities.forEach(function (quantity) {
      const rows = asArray(plot[quantity.key]);
      if (rows.length) sampleCount = Math.min(sampleCount, rows.length);
    });
    cache.t = new Float64Array(sampleCount);
    for (let i = 0; i < sampleCount; i++) cache.t[i] = numberOr(times[i], i > 0 ? cache.t[i - 1] : 0);
    cache.tEnd = Math.max(duration, sampleCount ? cache.t[sampleCount - 1] : 0);
    if (!(cache.tEnd > 0)) cache.tEnd = 1;
    cache.empty = false;

    const names = asArray(plot.joint_names);
    const limitPairs = {
      q: function (j) { return [asArray(plot.lower)[j], asArray(plot.upper)[j]]; },
      qd: function (j) { const v = asArray(plot.max_velocity)[j]; return isNumber(v) && v > 0 ? [-v, v] : []; },
      qdd: function (j) { const v = asArray(plot.max_acceleration)[j]; return isNumber(v) && v > 0 ? [-v, v] : []; },
    };
    for (let j = 0; j < jointCount; j++) {
      const joint = { name: names[j] !== undefined ? String(names[j]) : 'joint ' + (j + 1), rows: [] };
      PLOT.quantities.forEach(function (quantity) {
        const rows = asArray(plot[quantity.key]);
        const values = rows.length ? new Float64Array(sampleCount) : null;
        let lo = Infinity, hi = -Infinity;
        if (values) {
          for (let i = 0; i < sampleCount; i++) {
            const v = asArray(rows[i])[j];
            values[i] = isNumber(v) ? v : NaN;
            if (isNumber(v)) { if (v < lo) lo = v; if (v > hi) hi = v; }
          }
        }
        const limits = limitPairs[quantity.key](j).filter(isUsableLimit);
        limits.forEach(function (v) { if (v < lo) lo = v; if (v > hi) hi = v; });
        if (!isFinite(lo) || !isFinite(hi)) { lo = -1; hi = 1; }
        // axis labels: the limits when there are some, else the extremes of the data
        const labels = limits.length ? limits.slice() : (isFinite(lo) && values ? [hi, lo] : []);
        if (hi - lo < 1e-9) { const pad = Math.max(Math.abs(hi) * 0.1, 0.5); lo -= pad; hi += pad; }
        const margin = (hi - lo) * 0.06;
        joint.rows.push({ values: values, limits: limits, labels: labels, lo: lo - margin, hi: hi + margin, quantity: quantity });
      });
      cache.joints.push(joint);
    }
    return cache;
  }

  function buildPlots(robot) {
    const container = ui.plots;
    if (!container) return;
    container.innerHTML = '';
    plotEntries = [];
    plotData = preparePlotData(robot);
    if (plotData.empty) {
      container.innerHTML = '<p class="muted">No plot data.</p>';
      return;
    }
    plotData.joints.forEach(function (joint, j) {
      const block = document.createElement('div');
      block.className = 'joint';
      const name = document.createElement('div');
      name.className = 'joint-name';
      name.textContent = joint.name;
      const box = document.createElement('div');
      box.className = 'plot-box';
      box.title = 'Click or drag to set the time';
      const canvas = document.createElement('canvas');
      const overlay = document.createElement('canvas');
      overlay.className = 'plot-cursor';
      box.appendChild(canvas);
      box.appendChild(overlay);
      block.appendChild(name);
      block.appendChild(box);
      container.appendChild(block);
      const entry = { joint: j, canvas: canvas, overlay: overlay, width: 0 };
      plotEntries.push(entry);
      bindPlotScrub(box, entry);
    });
    drawAllPlots();
  }

  // Clicking or dragging on a plot sets the time.
  function bindPlotScrub(box, entry) {
    const seek = function (event) {
      const rect = box.getBoundingClientRect();
      const inner = entry.width - PLOT.left - PLOT.right;
      if (inner <= 0) return;
      setTime((event.clientX - rect.left - PLOT.left) / inner * plotData.tEnd);
    };
    box.addEventListener('pointerdown', function (event) {
      capturePointer(box, event);
      seek(event);
      const move = function (e) { seek(e); };
      const up = function () {
        box.removeEventListener('pointermove', move);
        box.removeEventListener('pointerup', up);
      };
      box.addEventListener('pointermove', move);
      box.addEventListener('pointerup', up);
    });
  }

  function sizeCanvas(canvas, width, height) {
    const ratio = window.devicePixelRatio || 1;
    canvas.width = Math.round(width * ratio);
    canvas.height = Math.round(height * ratio);
    canvas.style.width = width + 'px';
    canvas.style.height = height + 'px';
    const context = canvas.getContext('2d');
    context.setTransform(ratio, 0, 0, ratio, 0, 0);
    return context;
  }

  function rowTop(k) { return PLOT.top + k * (PLOT.rowHeight + PLOT.rowGap); }

  function drawAllPlots() {
    if (!ui.plots || !plotData || plotData.empty) return;
    lastPlotWidth = ui.plots.clientWidth;
    const width = Math.max(lastPlotWidth, 120);
    const plotWidth = width - PLOT.left - PLOT.right;
    const tEnd = plotData.tEnd;
    const tickStep = niceStep(tEnd / 5);
    const xOf = function (t) { return PLOT.left + (t / tEnd) * plotWidth; };

    plotEntries.forEach(function (entry) {
      entry.width = width;
      const joint = plotData.joints[entry.joint];
      const ctx = sizeCanvas(entry.canvas, width, PLOT.height);
      sizeCanvas(entry.overlay, width, PLOT.height);
      ctx.font = '10px system-ui, "DejaVu Sans", sans-serif';
      ctx.textBaseline = 'middle';

      joint.rows.forEach(function (row, k) {
        const top = rowTop(k);
        const h = PLOT.rowHeight;
        const yOf = function (v) { return top + h - (v - row.lo) / (row.hi - row.lo) * h; };
        ctx.fillStyle = '#1c1e21';
        ctx.fillRect(PLOT.left, top, plotWidth, h);

        // time grid
        ctx.strokeStyle = '#2f3237';
        ctx.lineWidth = 1;
        ctx.beginPath();
        for (let t = tickStep; t < tEnd - 1e-9; t += tickStep) {
          const x = Math.round(xOf(t)) + 0.5;
          ctx.moveTo(x, top);
          ctx.lineTo(x, top + h);
        }
        if (row.lo < 0 && row.hi > 0) {  // zero line
          const y = Math.round(yOf(0)) + 0.5;
          ctx.moveTo(PLOT.left, y);
          ctx.lineTo(PLOT.left + plotWidth, y);
        }
        ctx.stroke();

        // limits, dashed
        if (row.limits.length) {
          ctx.save();
          ctx.setLineDash([4, 3]);
          ctx.strokeStyle = PLOT.limitColor;
          ctx.beginPath();
          row.limits.forEach(function (v) {
            const y = Math.round(yOf(v)) + 0.5;
            ctx.moveTo(PLOT.left, y);
            ctx.lineTo(PLOT.left + plotWidth, y);
          });
          ctx.stroke();
          ctx.restore();
        }

        // the samples
        if (row.values) {
          ctx.save();
          ctx.beginPath();
          ctx.rect(PLOT.left, top, plotWidth, h);
          ctx.clip();
          ctx.strokeStyle = row.quantity.color;
          ctx.lineWidth = 1.4;
          ctx.beginPath();
          traceSeries(ctx, plotData.t, row.values, xOf, yOf, plotData.t.length > 2 * plotWidth);
          ctx.stroke();
          ctx.restore();
        }

        // labels: the quantity, and the limits (or the data's extremes) at their heights
        ctx.fillStyle = row.quantity.color;
        ctx.textAlign = 'left';
        ctx.fillText(row.quantity.label, 2, top + h / 2);
        ctx.fillStyle = '#8d939c';
        ctx.textAlign = 'right';
        let lastLabel = null;
        row.labels.forEach(function (v) {
          const text = formatValue(v);
          if (text === lastLabel) return;
          lastLabel = text;
          ctx.fillText(text, PLOT.left - 3, clamp(yOf(v), top + 5, top + h - 5));
        });
      });

      // time axis under the last row
      const axisY = rowTop(3) - PLOT.rowGap + PLOT.axisHeight / 2 + 1;
      ctx.fillStyle = '#8d939c';
      ctx.textAlign = 'center';
      for (let t = 0; t <= tEnd + 1e-9; t += tickStep) {
        const x = clamp(xOf(t), PLOT.left + 8, PLOT.left + plotWidth - 8);
        ctx.fillText(Number(t.toPrecision(6)) + (t === 0 ? ' s' : ''), x, axisY);
      }
    });
    drawPlotCursors();
  }

  // Adds one series to the current canvas path. With more samples than pixels (`decimate`), each
  // pixel column gets its first, lowest, highest and last value: the same picture, far fewer segments.
  function traceSeries(ctx, times, values, xOf, yOf, decimate) {
    let penDown = false;
    let column = null, first = 0, last = 0, low = 0, high = 0;
    const flush = function () {
      if (column === null) return;
      if (penDown) ctx.lineTo(column, first); else ctx.moveTo(column, first);
      ctx.lineTo(column, low);
      ctx.lineTo(column, high);
      ctx.lineTo(column, last);
      penDown = true;
      column = null;
    };
    for (let i = 0; i < times.length; i++) {
      const v = values[i];
      if (!isFinite(v)) { flush(); penDown = false; continue; }
      const x = xOf(times[i]);
      const y = yOf(v);
      if (!decimate) {
        if (penDown) ctx.lineTo(x, y); else ctx.moveTo(x, y);
        penDown = true;
        continue;
      }
      const c = Math.round(x);
      if (c !== column) {
        flush();
        column = c;
        first = last = low = high = y;
      } else {
        last = y;
        if (y < low) low = y;
        if (y > high) high = y;
      }
    }
    flush();
  }

  // The cheap per-frame part: a vertical line at the current time and a dot at each value.
  function drawPlotCursors() {
    if (!plotData || plotData.empty || !plotEntries.length) return;
    const where = bracket(plotData.t, currentTime);
    plotEntries.forEach(function (entry) {
      if (!entry.width) return;
      const ctx = entry.overlay.getContext('2d');
      ctx.clearRect(0, 0, entry.width, PLOT.height);
      const plotWidth = entry.width - PLOT.left - PLOT.right;
      const x = Math.round(PLOT.left + clamp(currentTime / plotData.tEnd, 0, 1) * plotWidth) + 0.5;
      ctx.strokeStyle = 'rgba(255, 255, 255, 0.75)';
      ctx.lineWidth = 1;
      ctx.beginPath();
      for (let k = 0; k < 3; k++) {
        ctx.moveTo(x, rowTop(k));
        ctx.lineTo(x, rowTop(k) + PLOT.rowHeight);
      }
      ctx.stroke();
      if (!where) return;
      const joint = plotData.joints[entry.joint];
      ctx.font = '10px system-ui, "DejaVu Sans", sans-serif';
      ctx.textBaseline = 'top';
      joint.rows.forEach(function (row, k) {
        if (!row.values) return;
        const v0 = row.values[where.i0];
        const v1 = row.values[where.i1];
        const v = v0 + (v1 - v0) * where.alpha;
        if (!isFinite(v)) return;
        const top = rowTop(k);
        const y = top + PLOT.rowHeight - (v - row.lo) / (row.hi - row.lo) * PLOT.rowHeight;
        ctx.fillStyle = row.quantity.color;
        ctx.beginPath();
        ctx.arc(x, y, 2.5, 0, 2 * Math.PI);
        ctx.fill();
        // current value, top right of the row
        const text = formatAtScale(v, row.hi - row.lo);
        ctx.textAlign = 'right';
        const textWidth = ctx.measureText(text).width;
        ctx.fillStyle = 'rgba(28, 30, 33, 0.8)';
        ctx.fillRect(PLOT.left + plotWidth - textWidth - 5, top + 1, textWidth + 4, 12);
        ctx.fillStyle = row.quantity.color;
        ctx.fillText(text, PLOT.left + plotWidth - 3, top + 2);
      });
    });
  }

  // ---------------------------------------------------------------------------------------------
  // The published state
  // ---------------------------------------------------------------------------------------------

  const state = { ready: false, errors: errors, load_ms: null, frames: 0, robots: [] };

  function publishState() {
    published = true;
    window.chaslesViewer = state;
    const element = document.getElementById('chasles-state');
    if (element) {
      try {
        element.textContent = JSON.stringify(state);
      } catch (error) {
        element.textContent = JSON.stringify({ ready: true, errors: errors.concat(['state: ' + describe(error)]) });
      }
    }
  }

  function worldPositionOf(object) {
    object.updateMatrixWorld(true);
    const p = object.getWorldPosition(new THREE.Vector3());
    return [p.x, p.y, p.z];
  }

  // The trail link's world position as drawn at t = 0 and at t = duration (read back from the
  // three.js group after posing the links), then back to t = 0.
  function measureTrails() {
    const trailGroup = function (robot) {
      return robot.trailIndex >= 0 && robot.times.length > 0 ? robot.links[robot.trailIndex].group : null;
    };
    setTime(0);
    const starts = robots.map(function (robot) { return trailGroup(robot) ? worldPositionOf(trailGroup(robot)) : null; });
    setTime(duration);
    const ends = robots.map(function (robot) { return trailGroup(robot) ? worldPositionOf(trailGroup(robot)) : null; });
    setTime(0);
    state.robots = robots.map(function (robot, index) { return { trail_start: starts[index], trail_end: ends[index] }; });
    // `frames`: the longest robot's frame count (robots of one view normally share their frame times)
    state.frames = robots.reduce(function (most, robot) { return Math.max(most, robot.times.length); }, 0);
  }

  // ---------------------------------------------------------------------------------------------
  // Start
  // ---------------------------------------------------------------------------------------------

  function start() {
    guarded('header', fillHeader);
    guarded('renderer', createRenderer);
    guarded('lights', addLights);
    guarded('scene objects', buildObjects);
    guarded('voxels', buildVoxels);
    viewRobots.forEach(function (data, index) { guarded('robot ' + index, function () { buildRobot(data, index); }); });
    guarded('markers', buildMarkers);
    guarded('notes', showNotes);
    if (!robots.length && !groups.objects.children.length && !groups.voxels.children.length && !markerMeshes.length) {
      const message = $('view-message');
      if (message && renderer) {
        message.textContent = 'This view has no robot and no scene objects.';
        message.hidden = false;
      }
    }
    robots.forEach(function (robot) { guarded(robot.name + ' bounds', function () { expandBoundsByRobot(robot); }); });
    guarded('camera', frameScene);
    guarded('toolbar', bindToolbar);
    guarded('display toggles', bindDisplayToggles);
    guarded('splitter', bindSplitter);
    guarded('time', function () { setTime(0); });
    guarded('robot panel', buildRobotSelector);
    guarded('first render', render);
    guarded('trail positions', measureTrails);

    state.ready = true;
    state.load_ms = Math.round(performance.now() * 10) / 10;
    publishState();

    window.addEventListener('resize', onLayoutChange);
    if (typeof ResizeObserver === 'function') {
      const observer = new ResizeObserver(onLayoutChange);
      if (viewElement) observer.observe(viewElement);
      if (ui.plots) observer.observe(ui.plots);
    }
    requestAnimationFrame(tick);
  }

  // Debugging and test hooks (the state itself is window.chaslesViewer).
  window.chaslesViewerApi = {
    setTime: function (t) { setTime(t); render(); },
    play: function () { setPlaying(true); },
    pause: function () { setPlaying(false); },
    get time() { return currentTime; },
    scene: scene,
    camera: camera,
  };

  try {
    start();
  } catch (error) {
    reportFailure('viewer', error);
    state.ready = true;
    state.load_ms = Math.round(performance.now() * 10) / 10;
    publishState();
  }
})();
