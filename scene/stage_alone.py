"""One stage of a scene's pipeline alone, as a one-row unit: ``make formal``'s
``stage_<name>`` proves a stage of one's own as it proves every unit (docs/formal.md,
"Proving a stage of your own").

The unit takes the fields the stage takes in its pipeline (the layout the stage before it
gives, as the stage names them) and gives what it gives; its uniforms are ports. Its datapath
is the stage's ``rtl`` on the unit's one ``hdl.unit.Pipeline``, so its registers are named
as a unit's are (``s<k>_<name>``), which the one-row harness's shadow reads. A stage with
handshakes of its own (``build``), loaded tables or ports of its own is not one-row and is
refused."""
from amaranth.hdl import Fragment

from hdl.fixed import Field, s, u
from hdl.unit import Unit
from hdl.units import PIPELINES

from . import registry
from .pipeline import ScenePipeline, _FromStages

__all__ = ["StageAlone", "one_row"]


def one_row(cls):
    """Whether a stage class has the one-row shape: its ``rtl`` on one shared enable."""
    return (cls.rtl is not registry.Stage.rtl and cls.build is registry.Stage.build
            and not cls.tables and not cls.ports)


def _field(name, shape):
    return Field(name, s(shape.width) if shape.signed else u(shape.width))


class StageAlone(Unit):
    NAME = "stage"
    DOC = "One stage of a scene's pipeline alone, as a one-row unit (make formal's stage_<name>)"
    # ``stage``: its name; the rest: the scene pipeline's parameters, of a pipeline that wants it
    PARAMS = _FromStages(lambda: {"stage": "colour", **ScenePipeline.PARAMS})
    RANGES = _FromStages(lambda: {"stage": tuple(c.name for c in registry.stages()[1:]),
                                  **ScenePipeline.RANGES})

    def validate(self, stage, **q):
        pipe = ScenePipeline.spec(**q)
        units = dict((st.name, (st, unit)) for st, unit in pipe.stage_units(
            pipe.raster.unit.o.payload.shape()))
        if stage not in units:
            raise ValueError(f"stage: {stage!r} is not in the pipeline of these parameters "
                             f"({', '.join(units)})")
        for _, each in units.values():     # built for their layouts; elaborated, so that
            Fragment.get(each, None)        # none is left unused (Amaranth would warn)
        self.stage, unit = units[stage]
        if not one_row(type(self.stage)):
            raise ValueError(f"stage: {stage!r} is not one-row (it has handshakes, tables or "
                             f"ports of its own)")
        self.inputs = [_field(unit.rename.get(n, n), f.shape)
                       for n, f in unit.i.payload.shape()]
        self.outputs = [_field(n, f.shape) for n, f in unit.o.payload.shape()]
        self.uniforms = list(self.stage.uniforms)

    @property
    def latency(self):
        return self.stage.latency

    def datapath(self, p, v):
        return self.stage.rtl(p, v, {f.name: getattr(self, f"u_{f.name}")
                                     for f in self.uniforms})


PIPELINES[StageAlone.NAME] = StageAlone
