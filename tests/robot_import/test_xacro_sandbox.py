"""A robot description is data (issue 36): a xacro copied from the shared M-20iA with
a payload in it runs no code, reads nothing outside the --package-path folders and
the description's package, and ends as one line naming the file and the expression,
exit 2, with no robot folder written. The unchanged copy still imports."""

import shutil
from pathlib import Path

import pytest
from test_import_fanuc import FANUC, pytestmark  # noqa: F401  (skip without ../shared)

from offline_prog.cli import main
from offline_prog.errors import InputError
from offline_prog.robot_import.sources import packages_for
from offline_prog.robot_import.xacro_sandbox import description_text

MARK = '<xacro:fanuc_m20ia prefix=""/>'


def material(text: str) -> str:
    """A top-level material whose name holds ``text`` (xacro expands it)."""
    return f'<material name="m{text}"><color rgba="1 1 1 1"/></material>'


def via_property(expression: str) -> str:
    """``$(eval ...)`` of an expression with parentheses, as the issue's example
    passes it: through a property (xacro's lexer ends ``$(...)`` at the first ``)``)."""
    return f'<xacro:property name="p" value="{expression}"/>' + material("$(eval ${p})")


@pytest.fixture(scope="module")
def packages(tmp_path_factory) -> Path:
    """A writable copy of the shared FANUC packages."""
    folder = tmp_path_factory.mktemp("pkgs") / "fanuc"
    shutil.copytree(FANUC, folder)
    return folder


def _payloads(pwned: Path, outside: Path) -> dict[str, tuple[str, str]]:
    """name -> (xacro text placed before the macro call, words the error must hold)."""
    system = f"import os; os.system('id > {pwned}')"
    return {
        "exec": (via_property(f"exec(&quot;{system}&quot;, dict())"), "exec is a Python builtin"),
        "attribute": (
            via_property("().__class__.__bases__[0].__subclasses__()"),
            "attribute access .__class__",
        ),
        "attribute_in_property": (
            material("${''.__class__.__mro__[1].__subclasses__()}"),
            "attribute access .__class__",
        ),
        "getattr_built_name": (
            via_property("getattr(dict, '_' + '_subclasses_' + '_')"),
            "getattr is a Python builtin",
        ),
        "import_from_chr": (
            via_property("eval(chr(95) * 2 + 'import' + chr(95) * 2 + '(&quot;os&quot;)')"),
            "eval is a Python builtin",
        ),
        "lambda": (material("${(lambda: 1)()}"), "a lambda is not allowed"),
        "comprehension": (material("${[c for c in 'ab']}"), "a comprehension is not allowed"),
        "open_in_eval": (via_property(f"open('{outside}').read()"), "open is a Python builtin"),
        "open_in_expression": (material(f"${{open('{outside}')}}"), "open is a Python builtin"),
        "python_vars": (material("${python.vars(python.type)}"), "python.vars is not allowed"),
        "load_yaml_outside": (
            material(f"${{xacro.load_yaml('{outside}')}}"),
            "outside the folders a description may read",
        ),
        "load_yaml_up": (
            material("${xacro.load_yaml('../../../../../../../../../etc/hostname')}"),
            "outside the folders a description may read",
        ),
        "env": (material("$(env HOME)"), "reads the user's environment"),
        "optenv": (material("$(optenv HOME nothing)"), "reads the user's environment"),
        "env_in_eval": (via_property("env('HOME')"), "env() reads the environment"),
        "cwd": (material("$(cwd)"), "names the working folder"),
        "absolute_include": (
            f'<xacro:include filename="{outside}"/>',
            "outside the folders a description may read",
        ),
        "optional_include": (
            f'<xacro:include filename="{outside}" optional="true"/>',
            "outside the folders a description may read",
        ),
        "power_bomb": (material("${9**9**9}"), "too large"),
    }


PAYLOADS = sorted(_payloads(Path("x"), Path("y")))


@pytest.mark.parametrize("payload", PAYLOADS)
def test_a_payload_is_one_line_exit_2_and_runs_nothing(packages, tmp_path, capsys, payload):
    pwned = tmp_path / "pwned.txt"
    outside = tmp_path / "secret.yaml"
    outside.write_text("token: Zq81xK\n")
    text, words = _payloads(pwned, outside)[payload]
    top = packages / "fanuc_m20ia_support" / "urdf" / f"evil_{payload}.xacro"
    source = (FANUC / "fanuc_m20ia_support/urdf/m20ia.xacro").read_text()
    top.write_text(source.replace(MARK, text + "\n" + MARK))
    out = tmp_path / "robots"
    argv = ["robots", "import", top, "--name", "evil", "--package-path", packages, "--out", out]
    code = main([str(a) for a in argv + ["--samples", "10"]])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert err[0].startswith(f"error: {top}: ") and words in err[0], err[0]
    assert "Zq81xK" not in err[0]
    assert not pwned.exists()
    assert not out.exists() or not any(out.iterdir())


def test_a_symbolic_link_out_of_the_package_is_refused(packages, tmp_path):
    """A link inside the package to a file elsewhere is resolved before the check:
    an include through it, and a mesh named through it, are refused."""
    outside = tmp_path / "outside.xacro"
    outside.write_text('<robot xmlns:xacro="http://wiki.ros.org/xacro"/>')
    urdf = packages / "fanuc_m20ia_support" / "urdf"
    (urdf / "linked.xacro").symlink_to(outside)
    top = urdf / "evil_link.xacro"
    source = (FANUC / "fanuc_m20ia_support/urdf/m20ia.xacro").read_text()
    include = '<xacro:include filename="$(find fanuc_m20ia_support)/urdf/linked.xacro"/>'
    top.write_text(source.replace(MARK, include + MARK))
    found = packages_for(top, [packages])
    with pytest.raises(InputError, match="outside the folders a description may read"):
        description_text(top, found)


@pytest.mark.parametrize(
    ("mesh", "words"),
    [
        ("package://fanuc_m20ia_support/../../../../../../../../etc/hostname", "outside"),
        ("/etc/hostname", "outside"),
        ("file:///etc/hostname", "--allow-file-meshes"),
    ],
)
def test_mesh_names_stay_in_the_packages(packages, tmp_path, capsys, mesh, words):
    macro = (FANUC / "fanuc_m20ia_support/urdf/m20ia_macro.xacro").read_text()
    name = f"m20ia_mesh_{abs(hash(mesh))}"
    urdf = packages / "fanuc_m20ia_support" / "urdf"
    first = "package://fanuc_m20ia_support/meshes/m20ia/visual/link_1.stl"
    (urdf / f"{name}_macro.xacro").write_text(macro.replace(first, mesh))
    source = (FANUC / "fanuc_m20ia_support/urdf/m20ia.xacro").read_text()
    top = urdf / f"{name}.xacro"
    top.write_text(source.replace("m20ia_macro.xacro", f"{name}_macro.xacro"))
    out = tmp_path / "robots"
    argv = ["robots", "import", top, "--name", "m", "--package-path", packages, "--out", out]
    code = main([str(a) for a in argv + ["--samples", "10"]])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and words in err[0] and mesh in err[0], err
    assert not (out / "m").exists()


def test_file_meshes_are_read_with_the_flag(packages, tmp_path):
    """--allow-file-meshes: a file:// mesh anywhere is converted as any other."""
    from offline_prog.robot_import.run import import_robot

    stl = tmp_path / "elsewhere" / "link_1.stl"
    stl.parent.mkdir()
    shutil.copyfile(FANUC / "fanuc_m20ia_support/meshes/m20ia/visual/link_1.stl", stl)
    macro = (FANUC / "fanuc_m20ia_support/urdf/m20ia_macro.xacro").read_text()
    urdf = packages / "fanuc_m20ia_support" / "urdf"
    first = "package://fanuc_m20ia_support/meshes/m20ia/visual/link_1.stl"
    (urdf / "file_mesh_macro.xacro").write_text(macro.replace(first, f"file://{stl}"))
    source = (FANUC / "fanuc_m20ia_support/urdf/m20ia.xacro").read_text()
    top = urdf / "file_mesh.xacro"
    top.write_text(source.replace("m20ia_macro.xacro", "file_mesh_macro.xacro"))
    result = import_robot(
        top,
        name="m",
        out=tmp_path / "robots",
        package_paths=[packages],
        samples=10,
        allow_file_meshes=True,
    )
    sources = (result.folder / "meshes" / "SOURCES.md").read_text()
    assert "| link_1 | visual | `link_1.stl` |" in sources
    assert str(tmp_path) not in sources


def test_what_descriptions_use_still_expands(tmp_path):
    """load_yaml inside the package (with xacro's !degrees, dotted access), $(arg),
    $(eval) arithmetic, $(find) includes and math names give xacro's values."""
    import xml.etree.ElementTree as ET

    pkg = tmp_path / "pkgs" / "demo_support"
    (pkg / "urdf").mkdir(parents=True)
    (pkg / "config").mkdir()
    (pkg / "package.xml").write_text("<package><name>demo_support</name></package>")
    (pkg / "config" / "joints.yaml").write_text("j1: {lower: !degrees -170, z: 0.5}\n")
    (pkg / "urdf" / "part.xacro").write_text(
        '<robot xmlns:xacro="http://wiki.ros.org/xacro">'
        '<xacro:property name="half" value="${pi/2}"/></robot>'
    )
    (pkg / "urdf" / "top.xacro").write_text(
        '<robot name="demo" xmlns:xacro="http://wiki.ros.org/xacro">'
        '<xacro:arg name="scale" default="2"/>'
        '<xacro:include filename="$(find demo_support)/urdf/part.xacro"/>'
        '<xacro:property name="cfg" value="${xacro.load_yaml('
        "'$(find demo_support)/config/joints.yaml')}\"/>"
        '<link name="a"/><link name="b"/>'
        '<joint name="j1" type="revolute"><parent link="a"/><child link="b"/>'
        '<origin xyz="0 0 ${cfg.j1.z * $(arg scale)}" rpy="0 0 ${half}"/>'
        "<limit lower=\"${cfg['j1']['lower']}\" upper=\"$(eval 2 * 1.5)\""
        ' velocity="${radians(90)}"/></joint></robot>'
    )
    text = description_text(pkg / "urdf" / "top.xacro", packages_for(pkg / "urdf/top.xacro", []))
    joint = ET.fromstring(text).find("joint")
    assert joint.find("origin").get("xyz") == "0 0 1.0"
    assert float(joint.find("origin").get("rpy").split()[2]) == pytest.approx(1.5707963267948966)
    limit = joint.find("limit")
    assert float(limit.get("lower")) == pytest.approx(-2.9670597283903604)
    assert limit.get("upper") == "3.0" and float(limit.get("velocity")) == pytest.approx(1.5707963)
