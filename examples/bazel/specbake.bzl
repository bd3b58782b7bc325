"""specbake as a Bazel action: macros over a genrule with declared inputs and predictable outputs.

Each macro runs the prebuilt specbake (@specbake//:specbake, see WORKSPACE) in the sandbox. specbake reads
only the files named on its command line and the files they reference, and the environment variables
SOURCE_DATE_EPOCH and SPECBAKE_OIIO_MODULE; its outputs are byte-identical for the same inputs whatever the
machine or thread count. So the action is hermetic and its results can come from a disk or remote cache.
"""

_TOOL = "@specbake//:specbake"
_MODULE = "@specbake//:oiio_module"

# The baked chains of one material or map pair, in the file names specbake writes.
_KINDS = ["roughness", "kernel", "lean", "lean_xy", "normal"]

def _check_container(container):
    # KTX2 and DDS hold a whole mip chain per file, so the outputs are known before the bake runs.
    if container not in ("ktx2", "dds"):
        fail("container must be ktx2 or dds (EXR and PNG outputs are not one file per chain), got " + container)

def _command(name, args, config):
    # The module is a declared input too: the environment variable stops the tool from looking for it
    # beside the executable's real path, outside the sandbox. --force: a stale output folder is rebaked.
    cmd = "SPECBAKE_OIIO_MODULE=$(execpath %s) $(execpath %s) -q -j 1" % (_MODULE, _TOOL)
    if config:
        cmd += " --config $(execpath %s)" % config
    return cmd + " " + args + " --force -o $(RULEDIR)/" + name

def _allow_roots(files):
    # Bazel's sandbox puts a symbolic link to each declared input in the execution root. specbake refuses a
    # reference that leads out of the scene's folder through a link unless its target's folder is named with
    # --allow-root, so name exactly the folders of the declared inputs' real files, and nothing else.
    return "".join([' --allow-root "$$(dirname "$$(readlink -f $(execpath %s))")"' % f for f in files])

def specbake_texture(name, normal, roughness = None, config = None, container = "ktx2", options = [], **kwargs):
    """Bakes one normal map (and roughness/ORM map) with `specbake texture`.

    Outputs: NAME/texture_{roughness,kernel,lean,lean_xy,normal}.CONTAINER and NAME/manifest.json.

    Args:
      name: target name and output folder.
      normal: the normal map.
      roughness: the roughness or ORM map (optional).
      config: a specbake TOML/JSON config file (optional).
      container: "ktx2" or "dds".
      options: more `specbake texture` options, e.g. ["--isotropic", "max"].
      **kwargs: passed to the genrule (visibility, tags, ...).
    """
    _check_container(container)
    srcs = [normal] + ([roughness] if roughness else []) + ([config] if config else [])
    args = "texture --normal $(execpath %s)" % normal
    if roughness:
        args += " --roughness $(execpath %s)" % roughness
    args += " --format " + container + "".join([" " + o for o in options])
    native.genrule(
        name = name,
        srcs = srcs,
        outs = ["%s/texture_%s.%s" % (name, kind, container) for kind in _KINDS] + [name + "/manifest.json"],
        cmd = _command(name, args, config),
        tools = [_TOOL, _MODULE],
        **kwargs
    )

def specbake_scene(name, scene, srcs = [], config = None, container = "ktx2", options = [], **kwargs):
    """Bakes one glTF/GLB scene with `specbake bake --format glb` (a self-contained GLB out).

    Outputs: NAME/<scene stem>.glb (carrying the baked textures of every material the plan bakes) and
    NAME/manifest.json.

    Args:
      name: target name and output folder.
      scene: the .gltf or .glb file.
      srcs: every file the scene references (buffers, textures). A file left out is not in the sandbox,
        and the bake fails naming it.
      config: a specbake TOML/JSON config file (optional).
      container: "ktx2" or "dds".
      options: more `specbake bake` options, e.g. ["--estimator", "second-order"].
      **kwargs: passed to the genrule.
    """
    _check_container(container)
    stem = scene.split(":")[-1].split("/")[-1].rsplit(".", 1)[0]
    outs = [name + "/" + stem + ".glb", name + "/manifest.json"]
    args = "bake $(execpath %s) --format glb --container %s" % (scene, container)
    args += _allow_roots([scene] + srcs)
    args += "".join([" " + o for o in options])
    native.genrule(
        name = name,
        srcs = [scene] + srcs + ([config] if config else []),
        outs = outs,
        cmd = _command(name, args, config),
        tools = [_TOOL, _MODULE],
        **kwargs
    )
