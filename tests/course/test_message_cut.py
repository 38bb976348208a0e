"""The cut of a long check message (``grader.table_message``): it keeps the message's end,
where the command to run next is said."""

from ptlab.course.grader import CUT, MAX_MESSAGE, cut_middle, table_message

COMMAND = "ptlab exercise inspect 9 answer.py --pixel 3,4 --seed 7 (the pixel that differs most)"


def test_a_short_message_is_kept_whole():
    assert cut_middle("D is normalised. " + COMMAND, MAX_MESSAGE) == "D is normalised. " + COMMAND


def test_a_long_message_keeps_its_start_and_its_last_clause():
    message = "the render differs. " + "a long hint about the lobe, " * 60 + "; to see where: " + COMMAND
    cut = table_message(message)
    assert len(cut) == MAX_MESSAGE
    assert cut.startswith("the render differs. ")
    assert cut.endswith("to see where: " + COMMAND)
    assert CUT in cut


def test_a_chinese_message_keeps_its_last_clause():
    message = "渲染不同。" + "很长的提示，" * 300 + "；逐个顶点查看哪里不同：" + COMMAND
    cut = cut_middle(message, MAX_MESSAGE)
    assert len(cut) == MAX_MESSAGE
    assert cut.endswith("逐个顶点查看哪里不同：" + COMMAND)


def test_a_last_sentence_longer_than_half_is_cut_too():
    message = "start. " + "x" * 3000
    cut = cut_middle(message, MAX_MESSAGE)
    assert len(cut) == MAX_MESSAGE
    assert cut.startswith("start. ")
    assert cut.endswith("x" * (MAX_MESSAGE // 2))
