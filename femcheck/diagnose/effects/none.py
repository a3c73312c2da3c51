"""``none``: the model as given explains the data within measurement noise (no parameters)."""
from femcheck.diagnose.effects import Effect


class NoEffect(Effect):
    id = "none"
    stage = 0
    params = ()

    def apply(self, model, readings, values, state) -> None:
        return None


EFFECT = NoEffect()
