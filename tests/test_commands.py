"""The exhibits' typed commands: every one read from its dict form, a bad one refused in one line
naming what is wrong, and a model refusing a command it does not take."""

import math

import pytest

from mechviz.dynamics import SettingError
from mechviz.viz.model import CyclotronModel, HoopModel
from mechviz.viz.model.commands import COMMANDS, Kick, Reset, Set, as_dict, parse

# every command class, as a dict (the form a file or another program writes) and as the value
EXAMPLES = [
    ({"op": "reset"}, Reset()),
    ({"op": "set", "method": "rk4", "dt": 0.02}, Set(fields={"method": "rk4", "dt": 0.02})),
    ({"op": "set", "params": {"field": 2.0}}, Set(params={"field": 2.0})),
    (
        {"op": "set", "mode": "custom", "angles": [0.1, 0.2], "params": {"bead_mass": 0.5}},
        Set(fields={"mode": "custom", "angles": [0.1, 0.2]}, params={"bead_mass": 0.5}),
    ),
    ({"op": "kick", "dv": 0.5}, Kick(dv=0.5)),
    ({"op": "kick"}, Kick()),
]


def test_the_examples_hold_every_command_class():
    assert {type(c) for _, c in EXAMPLES} == set(COMMANDS)


@pytest.mark.parametrize(("form", "command"), EXAMPLES)
def test_every_command_round_trips_through_parse(form, command):
    assert parse(form) == command
    assert parse(as_dict(command)) == command
    assert as_dict(parse(form)) == {**form, **({"dv": None} if form == {"op": "kick"} else {})}


def test_a_bare_op_is_a_command_without_fields():
    assert parse("reset") == Reset()
    assert parse("kick") == Kick()


@pytest.mark.parametrize(
    ("form", "field", "words"),
    [
        ({"op": "kick", "dv": "fast"}, "dv", "got `str`"),
        ({"op": "kick", "dv": math.inf}, "dv", "finite"),
        ({"op": "kick", "strength": 1.0}, "strength", "not a field of kick (it takes dv)"),
        ({"op": "reset", "hard": True}, "hard", "not a field of reset"),
        ({"op": "set", "params": {"mass": 1.0, "field": "strong"}}, "params.field", "got `str`"),
        ({"op": "set", "params": [1.0]}, "params", "got `array`"),
    ],
)
def test_a_bad_field_is_one_line_naming_it(form, field, words):
    with pytest.raises(SettingError) as err:
        parse(form)
    message = str(err.value)
    assert err.value.field == field and message.startswith(field), message
    assert words in message and "\n" not in message


@pytest.mark.parametrize(
    ("form", "named"), [({"op": "jump"}, "'jump'"), ({"dv": 0.5}, "None"), ("fly", "'fly'")]
)
def test_an_unknown_op_is_one_line_naming_it_and_the_ops(form, named):
    with pytest.raises(ValueError) as err:
        parse(form)
    assert str(err.value) == f"op must be one of reset, set, kick; got {named}"


def test_a_command_checks_itself_when_built():
    with pytest.raises(SettingError, match="dv must be finite"):
        Kick(dv=math.nan)
    with pytest.raises(SettingError, match=r"Set\.params"):
        Set(fields={"params": {"mass": 1.0}})
    with pytest.raises(AttributeError):
        Kick(dv=1.0).dv = 2.0  # frozen


def test_a_model_refuses_a_command_it_does_not_take_and_changes_nothing():
    hoop = HoopModel()
    config, revision = hoop.config, hoop.revision
    with pytest.raises(
        ValueError, match=r"^hoop takes no kick command; op must be one of reset, set$"
    ):
        hoop.apply(Kick(dv=0.5))
    with pytest.raises(ValueError, match=r"a command must be one of reset, set .*'op': 'reset'"):
        hoop.apply({"op": "reset"})  # a dict goes through parse first
    assert hoop.config is config and hoop.revision == revision


def test_a_parsed_command_applies_as_the_typed_one():
    """A kick read from its dict form moves the charge's circle as the typed kick does."""
    a, b = CyclotronModel(), CyclotronModel()
    for m in (a, b):
        m.advance(1.0)
    a.apply(Kick(dv=0.5))
    b.apply(parse({"op": "kick", "dv": 0.5}))
    assert a.theory_radius == b.theory_radius and (a.state == b.state).all()
    assert CyclotronModel.commands == (Reset, Set, Kick)


def test_a_view_observing_a_model_is_told_of_every_change_and_of_none_after_it_stops():
    """The viewer draws an exhibit when its model says it changed (``observe``), not by
    comparing counters every frame: a command, an advance and a reset each tell the observer;
    a refused command tells nothing; once stopped, nothing more."""
    hoop = HoopModel()
    told: list[int] = []
    stop = hoop.observe(lambda model: told.append(model.revision))
    hoop.apply(Set(fields={"amplitude": 0.3}))
    assert told and told[-1] == hoop.revision
    n = len(told)
    hoop.advance(0.05)
    assert len(told) > n
    n = len(told)
    with pytest.raises(ValueError):
        hoop.apply(Set(fields={"method": "no such method"}))
    assert len(told) == n
    hoop.apply(Reset())
    assert len(told) > n
    stop()
    n = len(told)
    hoop.advance(0.05)
    hoop.apply(Reset())
    assert len(told) == n


def test_each_view_is_built_over_its_model_sees_what_is_done_to_the_model_alone_until_closed(
    server,
):
    """A view is not its model: every exhibit of the registry draws a model of the class the
    models' registry names for its system, kept as ``model`` (the view answers none of the
    model's calls). A step or a command given to the model alone marks the view to draw, and a
    new start is built into the view at once (the hoop's body for its new radius); once the
    view is closed, nothing done to the model reaches it."""
    from mechviz.viz.model import MODELS, ExhibitModel
    from mechviz.viz.scene import EXHIBITS

    for key, cls in EXHIBITS.items():
        assert not issubclass(cls, ExhibitModel), key
        assert cls.model_type is MODELS[key], key
        model = MODELS[key]()
        view = cls(server, model)
        assert view.model is model and type(view.model) is MODELS[key], key
        assert not any(hasattr(view, name) for name in ("advance", "apply", "state", "t")), key
        assert view.draw_if_changed() and not view.to_draw, key  # drawn once, then up to date
        model.advance(0.05)
        assert view.to_draw, key
        view.draw_if_changed()
        model.apply(Reset())
        assert view.to_draw and view.draw_if_changed(), key
        view.close()
        model.advance(0.05)
        model.apply(Reset())
        assert not view.to_draw, key

    hoop = HoopModel()
    view = EXHIBITS[hoop.key](server, hoop)
    radius = hoop.params.radius
    hoop.apply(Set(params={"radius": 2 * radius}))
    assert view._built_radius == 2 * radius  # the view built the new start's hoop
    view.close()
    hoop.apply(Set(params={"radius": radius}))
    assert view._built_radius == 2 * radius  # closed: the model's new start is not its own

    cyclotron = CyclotronModel()
    view = EXHIBITS[cyclotron.key](server, cyclotron)
    view.draw()
    cyclotron.apply(Kick(dv=0.5))  # the model alone: the view keeps the orbit before the kick
    assert view.ghost_ring.visible
