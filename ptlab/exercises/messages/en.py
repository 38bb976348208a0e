# ruff: noqa: E501 (a catalogue: a message a line reads best)
"""The graders' texts in English, by message id (``ptlab.exercises.messages``): what
``zh`` says in Chinese, with the same ids and the same fields."""

_ROWS = ("top", "upper middle", "lower middle", "bottom")
_COLUMNS = ("left", "centre left", "centre right", "right")

MESSAGES: dict[str, str] = {
    # What many messages share.
    "aside": " ({hint})",
    "quoted": "'{name}'",
    "channel.red": "red",
    "channel.green": "green",
    "channel.blue": "blue",
    # The score table (grader.Grade.table).
    "table.chapter": "Chapter {number}: {title}  ({file})",
    "table.check": "check",
    "table.points": "points",
    "table.verdict": "verdict",
    "table.message": "message",
    "table.pass": "pass",
    "table.fail": "FAIL",
    "table.total": "total",
    "table.full_marks": "full marks  ",
    "table.seed": "{full_marks}grading seed {seed} (--grading-seed {seed} grades again with the same inputs)",
    # The grader (grader.py).
    "grader.overall_limit": "not run: grading reached its overall limit of {seconds:.0f} s",
    "grader.not_run": "not run: {message}",
    "grader.timeout": "took longer than {seconds:.3g} s and was stopped, in {during} "
    "(an endless loop, or a Python loop over every ray?)",
    "grader.outside": "{error_type}: {error} (raised outside your file)",
    "grader.outside_place": "raised outside your file",
    "grader.not_written": "{name}is not written yet: it still raises NotImplementedError ({place})",
    "grader.student_error": "{error_type}: {error} ({place})",
    "grader.and": " and ",
    "grader.not_graded_until_one": "not graded until {names} passes",
    "grader.not_graded_until": "not graded until {names} pass",
    "grader.gated_says": "{not_graded}; {name} says: {message}",
    "grader.gated_passes": "{not_graded}; by itself it passes: {message}",
    "grader.gated_fails": "{not_graded}; by itself it fails: {message}",
    # What the student's functions return (chapter.py, finite.py).
    "array.shape": "{name} must return an array of shape {expected}, yours has shape {shape}",
    "array.not_finite": "{name} returned NaN or infinite values{hint}",
    "require.missing": "your file has no function {names} (keep the names of the exercise file)",
    "require.library_answer": "{name}: this is ptlab's own answer ({origin}), not yours: write it in your file",
    "require.copied": "your file holds {copied}: write your own",
    "returned": "what {name} returned",
    "at_row": "row {row} of {rows}",
    "at_column": ", column {column}",
    "at_pixel": "pixel (x={x}, y={y}) ({channel}; x=0, y=0 is the top left)",
    "in_pass": " in pass {number} of {passes}",
    "not_finite": "{what} has {kind} at {where}",
    "not_finite.more": " and {others} more NaN or infinite values",
    # Renders compared with the library's (renders.py).
    "render.path_traced": "the path-traced Cornell box through {yours}",
    "render.normals": "the Cornell box's normals seen through {yours}",
    "render.missing": "through {yours} the camera sees nothing in {share:.0%} of the pixels "
    "where the library sees a wall ({hint})",
    "render.normals_differ": "{what} differ from the library's by {difference:.4f} on average",
    "render.normals_match": "the Cornell box seen through {yours} matches",
    "render.yours": "{what}: your render",
    "render.matches": "{what}: every region within {threshold:.1f} standard errors of the library's, "
    "no noisier than a right answer (whole image {overall:.3f}x as bright)",
    "render.differs": "{what}: {difference}",
    "render.and": "; and {difference}",
    "render.mean_brighter": "{wrong} of {tests} regions and colours differ from the library's picture "
    "beyond the noise; the worst, {region}, is brighter ({ratio:.2f}x, {t:.0f} standard errors off; "
    "a right answer stays within {threshold:.1f}); the whole image is {overall:.2f}x as bright",
    "render.mean_darker": "{wrong} of {tests} regions and colours differ from the library's picture "
    "beyond the noise; the worst, {region}, is darker ({ratio:.2f}x, {t:.0f} standard errors off; "
    "a right answer stays within {threshold:.1f}); the whole image is {overall:.2f}x as bright",
    "render.its": "its",
    "render.too_clean": "too clean for {spp} samples per pixel: this is not a render of these samples "
    "(your passes' variance is {low:.3g} times the library's at the same samples per pixel in half the "
    "picture's {regions} regions, {total:.3g} times over the whole picture, where a right answer's is at "
    "least 1/{clean_ratio:g} of it, with chance at least {bound:.3g}: this test fails a right answer with "
    "probability at most {false_alarm:g})",
    "render.too_noisy": "too noisy: your passes' variance is {median:.3g} times the library's at the same "
    "samples per pixel in half the picture's {regions} regions ({total:.3g} times over the whole picture), "
    "where a right answer's is at most {noise_ratio:g} times (with chance, at most {bound:.3g}: this test "
    "fails a right answer with probability at most {false_alarm:g})",
    "region.channel": "the {channel} of {region}",
    **{
        f"region.{row}.{column}": f"the {_ROWS[row]} {_COLUMNS[column]} region"
        for row in range(4)
        for column in range(4)
    },
    # Chapter 1: cameras and primary rays (chapters/ch01_cameras.py).
    "ch01.title": "Cameras and primary rays",
    "ch01.check.centre ray": "centre ray",
    "ch01.check.unit directions": "unit directions",
    "ch01.check.field of view": "field of view",
    "ch01.check.image orientation": "image orientation",
    "ch01.check.jittered rays": "jittered rays",
    "ch01.check.render": "render",
    "ch01.two_arrays": "generate_rays must return two arrays: (origins, dirs)",
    "ch01.shapes": "expected origins and dirs of shape ({n}, 3), got {origins} and {dirs}",
    "ch01.row": "row {row} (the ray through pixel x={x}, y={y})",
    "ch01.origins": "the origin array generate_rays returned",
    "ch01.dirs": "the direction array generate_rays returned",
    "ch01.eye": "the ray should start at the eye {eye}, not {yours}",
    "ch01.centre": "the ray through the image's centre should go along forward {forward}, not {yours}",
    "ch01.centre_ok": "the centre ray goes along forward, and the corners' rays fan out from it",
    "ch01.fan": "the rays through the four corner pixels should fan out from the centre ray, each its own "
    "way; yours go (nearly) the same way as it or as each other (a direction must depend on its pixel)",
    "ch01.length": "directions must have length 1; one has length {length:.4f} (normalise them)",
    "ch01.length_ok": "every direction has length 1",
    "ch01.top_edge": "the top edge should be fov_y / 2 = {expected:.2f} degrees off forward, yours is {yours:.2f}",
    "ch01.left_edge": "the left edge should be atan(tan(fov_y / 2) * width / height) = {expected:.2f} degrees "
    "off forward, yours is {yours:.2f} (the aspect ratio?)",
    "ch01.fov_ok": "the image spans fov_y vertically, times the aspect ratio across",
    "ch01.hint.degrees": "fov_y is in degrees: math.tan takes radians (math.radians(fov_y))",
    "ch01.hint.whole_fov": "tan(fov_y / 2) reaches the top edge: the whole fov_y is twice that",
    "ch01.hint.aspect_on_y": "the aspect ratio (width / height) widens x, not y",
    "ch01.hint.aspect_divides_y": "the aspect ratio (width / height) widens x; y is not divided by it",
    "ch01.hint.rows_down": "rows go down, y up",
    "ch01.hint.turned_over": "tan({half:g}) < 0 turns the image over: fov_y is in degrees, and math.tan "
    "takes radians (math.radians(fov_y))",
    "ch01.top": "pixel (0, 0) should be at the top of the image ({hint})",
    "ch01.left": "pixel (0, 0) should be on the left of the image (x grows to the right)",
    "ch01.orientation_ok": "pixel (0, 0) is the top-left corner",
    "ch01.jittered": "rays through jittered points differ from the pinhole model's by up to {worst:.4f}",
    "ch01.jittered_ok": "200 jittered rays match the pinhole model",
    "ch01.hint.u_ignored": "u is ignored: the ray goes through the pixel's centre; the point is pixel + u",
    "ch01.hint.extra_half": "u is added, and half a pixel more: the point is pixel + u, u already spans the pixel",
    "ch01.hint.u_swapped": "u[:, 0] goes with x and u[:, 1] with y",
    "ch01.hint.u_subtracted": "the point is pixel + u, not pixel - u",
    "ch01.hint.jitter": "is u added to the pixel coordinates, and nothing else?",
    "ch01.yours": "your rays",
    "ch01.nan_hint": "rays too long for float32, the renderer's precision?",
    # Chapter 2: Ray-triangle intersection (Möller–Trumbore) (chapters/ch02_ray_triangle.py).
    "ch02.title": "Ray-triangle intersection (Möller–Trumbore)",
    "ch02.check.known hits": "known hits",
    "ch02.check.outside each edge": "outside each edge",
    "ch02.check.parallel rays": "parallel rays",
    "ch02.check.behind the origin": "behind the origin",
    "ch02.check.both faces": "both faces",
    "ch02.check.many rays": "many rays",
    "ch02.check.barycentrics": "barycentrics",
    "ch02.check.render": "render",
    # Chapter 3: Whitted ray tracing: reflection, refraction, Fresnel (chapters/ch03_whitted.py).
    "ch03.title": "Whitted ray tracing: reflection, refraction, Fresnel",
    "ch03.check.reflect": "reflect",
    "ch03.check.refract": "refract",
    "ch03.check.fresnel": "fresnel",
    "ch03.check.total internal reflection": "total internal reflection",
    "ch03.check.render": "render",
    # Chapter 4: Bounding boxes: the slab test (chapters/ch04_bounding_boxes.py).
    "ch04.title": "Bounding boxes: the slab test",
    "ch04.check.entering a box": "entering a box",
    "ch04.check.going backwards": "going backwards",
    "ch04.check.misses": "misses",
    "ch04.check.starting inside": "starting inside",
    "ch04.check.parallel to a slab": "parallel to a slab",
    "ch04.check.flat boxes": "flat boxes",
    "ch04.check.render": "render",
    # Chapter 5: The BVH: building with the SAH, and traversal (chapters/ch05_bvh.py).
    "ch05.title": "The BVH: building with the SAH, and traversal",
    "ch05.check.SAH costs": "SAH costs",
    "ch05.check.empty sides": "empty sides",
    "ch05.check.best split": "best split",
    "ch05.check.near child first": "near child first",
    "ch05.check.closest hits": "closest hits",
    "ch05.check.tree quality": "tree quality",
    "ch05.check.traversal order": "traversal order",
    "ch05.check.render": "render",
    # Chapter 6: Monte Carlo and the diffuse material (chapters/ch06_diffuse.py).
    "ch06.title": "Monte Carlo and the diffuse material",
    "ch06.check.eval": "eval",
    "ch06.check.sample": "sample",
    "ch06.check.pdf integrates to 1": "pdf integrates to 1",
    "ch06.check.material harness": "material harness",
    "ch06.check.render": "render",
    # Chapter 7: Path tracing: the homework's castRay (chapters/ch07_path_tracing.py).
    "ch07.title": "Path tracing: the homework's castRay",
    "ch07.check.direct light": "direct light",
    "ch07.check.roulette unbiased": "roulette unbiased",
    "ch07.check.indirect bounce": "indirect bounce",
    "ch07.check.light not black": "light not black",
    "ch07.check.lights one-sided": "lights one-sided",
    "ch07.check.white furnace": "white furnace",
    "ch07.check.Cornell box": "Cornell box",
    # Chapter 8: Parallel rendering over tiles (chapters/ch08_parallel.py).
    "ch08.title": "Parallel rendering over tiles",
    "ch08.check.tiles": "tiles",
    "ch08.check.tile job": "tile job",
    "ch08.check.parallel": "parallel",
    "ch08.check.any worker count": "any worker count",
    "ch08.check.matches the library": "matches the library",
    # Chapter 9: Microfacet materials (chapters/ch09_microfacet.py).
    "ch09.title": "Microfacet materials",
    "ch09.check.D normalisation": "D normalisation",
    "ch09.check.Smith G": "Smith G",
    "ch09.check.Fresnel-Schlick": "Fresnel-Schlick",
    "ch09.check.eval": "eval",
    "ch09.check.harness (hemisphere)": "harness (hemisphere)",
    "ch09.check.render (hemisphere)": "render (hemisphere)",
    "ch09.check.harness (importance)": "harness (importance)",
    "ch09.check.render (importance)": "render (importance)",
    # Chapter 10: Multiple importance sampling (chapters/ch10_mis.py).
    "ch10.title": "Multiple importance sampling",
    "ch10.check.balance heuristic": "balance heuristic",
    "ch10.check.power heuristic": "power heuristic",
    "ch10.check.weights sum to 1": "weights sum to 1",
    "ch10.check.zero and delta pdfs": "zero and delta pdfs",
    "ch10.check.render": "render",
}
