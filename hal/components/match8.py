"""match8: true when the cascade input ``in`` is true and ``a0``..``a7`` equal ``b0``..``b7``
bit for bit (chain several through ``in`` for wider words)."""

from hal.api import RtComponent, funct, pin


class Match8(RtComponent):
    in_ = pin("bit in", default=1)
    a = pin("bit in", "a{}", count=8)
    b = pin("bit in", "b{}", count=8)
    out = pin("bit out")

    @funct()
    def update(self, period: int) -> None:
        a, b = self.a, self.b
        self.out = self.in_ and all(a[i] == b[i] for i in range(8))


COMPONENT = Match8
