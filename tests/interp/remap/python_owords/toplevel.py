import oword
