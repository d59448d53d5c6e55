MODULE MainModule
    !*********************?????????****************************************************************!

    PROC main()

        !*********************??TCP/IP?????***************************
               TCP_Connections;
        !MoveL offs(p10,0,0,20), v100, z0, toolnew\WObj:=wobj0;
        !MoveL p10, v100, z0, toolnew\WObj:=wobj0;
       
    ENDPROC




ENDMODULE