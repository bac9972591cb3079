"""--arm.audit: the trials the audit draws are labelled by a person too, blind to the camera's label, and both labels
reach the journal (or, audited in the viewer, the camera's label at once, marked drawn); the others never ask."""

from types import SimpleNamespace

import pytest

from lerobot_contrast.contrast.audited import audited
from lerobot_contrast.operators.arm.args import ArmArgs
from lerobot_contrast.operators.arm.operator import ArmOperator
from lerobot_contrast.operators.base import Label
from lerobot_contrast.spine.runner import _label_notes


class Person:
    def __init__(self, answer: Label):
        self.answer, self.asked, self.said = answer, [], []

    def label(self, subgoals, suggestion, early):
        self.asked.append(suggestion)
        return self.answer

    def say(self, text):
        self.said.append(text)


def arm(person: Person, share: float, index: int) -> ArmOperator:
    operator = ArmOperator.__new__(ArmOperator)  # its camera and motions are not needed to label
    operator.person, operator.args, operator.seed = person, ArmArgs(audit=share), 11
    operator.context = SimpleNamespace(index=index)
    operator._label = lambda subgoals: Label("done", success=True, progress=1.0)  # the camera says success
    return operator


def test_an_audited_trial_gets_the_persons_label_beside_the_cameras():
    index = next(i for i in range(100) if audited(11, i, 0.2))
    person = Person(Label("done", success=False, progress=0.0))
    label = arm(person, 0.2, index).label([], None, None)
    assert (label.success, label.audit) == (True, False)  # the camera's label stands; the person's beside it
    assert person.asked == [None]  # asked without the camera's verdict as a suggestion
    assert _label_notes(label) == {"audit": False, "audit_drawn": True}


def test_with_the_audit_in_the_viewer_the_camera_label_is_journalled_at_once_and_marked_drawn():
    index = next(i for i in range(100) if audited(11, i, 0.2))
    person = Person(Label("done", success=False))
    operator = arm(person, 0.2, index)
    operator.args = ArmArgs(audit=0.2, audit_at="viewer")
    label = operator.label([], None, None)
    assert (label.success, label.audit, person.asked) == (True, None, [])  # nobody asked at the bench
    assert _label_notes(label) == {"audit_drawn": True}
    assert "audit page" in person.said[-1]


def test_a_trial_not_drawn_never_asks_and_a_person_may_still_stop():
    index = next(i for i in range(100) if not audited(11, i, 0.2))
    person = Person(Label("done", success=False))
    assert arm(person, 0.2, index).label([], None, None).audit is None and person.asked == []
    drawn = next(i for i in range(100) if audited(11, i, 0.2))
    assert arm(Person(Label("stop")), 0.2, drawn).label([], None, None).action == "stop"


@pytest.mark.parametrize("share", [-0.1, 1.5])
def test_a_share_outside_0_to_1_is_one_line(share):
    from lerobot_contrast.contrast.errors import UserError
    from lerobot_contrast.operators.arm.setup import arm_operator

    with pytest.raises(UserError, match=rf"--arm.audit={share:g}: give the share of trials a person labels too"):
        arm_operator(ArmArgs(audit=share), None, None, None, None, lambda: None, 0)
