"""An attack: chapter 7's four functions, the student's own (a right answer), carried
compressed and base64-encoded and compiled at import, so that the file's text shows none of
them: a teacher reading the file, and the grader's reading of it (authorship, pairs of
students alike), see nothing. It had full marks."""

import base64
import zlib

_CODE = (
    "eNqdVk2P2zYQvftXEDkU1C6t3U0uxSIOkKAFWqBIAgRBD0Eg0NLIJiKRKkl5sz30t2c4pCRq7QRtdZFMvnkcvvmy"
    "6gdjPdNjPzwy6ZgeNpvWmp4NvpP7UmkPByu9sa4cpD8yFfEffnv9y7s/q1/ff/j9j3dvBXuPe04w2TSVN1Wrul4w"
    "d5QN4Gu0rayhOiqfMzvZDx1YNzG+MaOu4aNWrbG9y5EnqMP5E7AxXjAvv0BlzYPbbDYNtKxRFlFVpw5Hz9PxNWg8"
    "XtY1dILh6YKNxf2G4UMwtouQUlqQ0dIlr/hYEA6vMkHpXQ4GBXFsG+jKgTCNcv45AtAtPuHFbBl5HhQCZrIbFLl0"
    "f1nPybb4dC/YW6PhM2Fr4yp/BC/RBHG9/Kr6seeBPhyqBbIVgt0Wa/TsaGazDUbRcY2iys6tjY1VB6XRhm7Drult"
    "2taBn31iV7Sqox7SHuBMjev0M1qiwepIMjwpp/YdoOU/FI/S1HU3NtDw6IOYqLdsWrjD73WWRafbELeQWZxC+gxO"
    "sntG8S0fTLhf/NYR7WpJx04OXGX6Xp2pd8NiSOY7DE1bhfSIZFl2pxwj4dTXlGClP1ozHo7DGFRoZxYrGyUxuXGB"
    "/JnFjbQW/Gg160BzjE5KaDs6h0aY42MH3gNfuAUbKmuXbE72I3uZNjI3KNfazkj/4jkPuxM/OoKslqcqieVBxXpS"
    "J0jMlLe52LE8MrlTSo7/JzYo7hM8rnwf/qQw5N5RUSyoVGuwFMLDESzwcM4rdgfbn0VGcpNXCkIEIag4Sun84wB8"
    "kS61g0XX3eV4x8PXBe1UA7k7a6fZqx27FVnlCbZdfuR16rJCDZyXSzT0xHha20mvjf4brOFTWPN8oZad6s/t5oY6"
    "rQiiQj2wtebbwfW4Q2SrZ9EjM8gTN1FSyezm4vkUlj9f4HMAroJeYSkYTfgGOi8TnsVspPX4GTemFPc2jJ2Brnlp"
    "JAxxZqVBhB9YZ0of3FRW8jEoeRsz21jWwBAGoMYdfQA+wUMSVXHvmt0l4/CgX4EgNrwwSK3DGcXp2HJWOf4MIhez"
    "JR19vaOWEFjKwaq+yIlD4SxzdaridKNgsqBVO/FEGrbDS92vxN5ji/syr6Dg2BqaMLLmIMZJOYUiNT5iu2JEvQoV"
    "+4kAOMO1fzLe/nsfTe6sLhTlxoucB+FHNxvxTuv/GXyO/pJFItKfh+Nf/skoI6BYCFL5nV1ud97m14glKUvq+OWM"
    "y9gp6vRv5kJLL/euaXmxdPaneRHzj8T/cWqkthHE2HwD0Z1ESQ=="
)

exec(zlib.decompress(base64.b64decode(_CODE)))
