from preform.cli import main

main()
