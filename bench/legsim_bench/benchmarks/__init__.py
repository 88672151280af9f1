"""The benchmark programs (work-precision, option cost, stress, MCU) and the peer engines.

Apart from the bench proper (the parent package: scenes over CAN, the reference model and
its checks), these measure the core in-process and compare it with other engines.
"""
