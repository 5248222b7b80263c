"""Hardware counts from Yosys against the seeds' own counts."""
from flows.report import count, file_tag


def test_power_unit_is_the_patents_three_multiplies_and_five_add_subtracts(tmp_path):
    c = count("fenney_power", work=tmp_path)
    assert (c["mul"], c["const_mul"], c["add"]) == (3, 0, 5)


def test_illumination_has_table_1s_multipliers_and_luts(tmp_path):
    """Seed 003 Table 1: 2 multipliers and 8 LUTs (6 cosine tables, diffuse, specular)."""
    c = count("illum", work=tmp_path)
    assert (c["mul"], c["const_mul"], c["tables"]) == (2, 0, 8)


def test_peercy_baseline_counts(tmp_path):
    """The Cartesian baseline (seed 003 Table 1's Peercy): two 3x3 matrix-vector products (18
    multipliers), |L_t|^2, |H_t|^2 and the two dot products with the bump normal (12), and one
    scaling multiply per output (2); the normalisation a reciprocal square root table per
    vector (2 look-ups) instead of 9 dividers and 3 square roots."""
    c = count("peercy", work=tmp_path)
    assert (c["mul"], c["const_mul"], c["tables"]) == (32, 0, 2)


def test_a_scene_pipelines_files_have_names_the_file_system_takes():
    """A unit's build files are named by its parameters, but a scene pipeline's (its own
    parameters and every stage's: 31 at the defaults) would pass a file name's 255 bytes
    (make tradeoffs failed so on a stage with one more); past 120 characters they are a
    digest, one per parameter set."""
    from scene.pipeline import ScenePipeline
    params = dict(ScenePipeline.PARAMS)
    long = file_tag("scene", params)
    assert len(long) < 40 and long.startswith("scene-")
    assert file_tag("scene", {**params, "lights": 2}) != long
    assert file_tag("colour", {"lights": 2}) == "colour-lights=2"
