from ecattool.cli import main

main()
